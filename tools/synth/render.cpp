#include "render.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>

extern "C" {
#include "mvod/calib.h"
}

#include <algorithm>
#include <cmath>

namespace synth {

namespace {

constexpr int kTile = 16;       // pixels per tile side: the unit of culling and of threading
constexpr double kNear = 0.05;  // metres: nothing nearer the camera is drawn

// Distant surfaces fade into the sky between these ranges (metres), so that geometry beyond
// the last one can be skipped without anything popping into view.
constexpr double kHazeStart = 50, kHazeEnd = 100;

// A featureless sky, brighter towards the zenith. elevation = sine of the angle above the horizon.
float sky_grey(double elevation)
{
	return float(170 + 60 * elevation);
}

float haze(double range)
{
	const double k = std::clamp((range - kHazeStart) / (kHazeEnd - kHazeStart), 0.0, 1.0);
	return float(k * k * (3 - 2 * k));
}

bool overlaps(const cv::Rect2d &a, const cv::Rect2d &b)
{
	return a.x <= b.x + b.width && b.x <= a.x + a.width && a.y <= b.y + b.height && b.y <= a.y + a.height;
}

// Normalised image coordinates (the ray with z = 1) behind each pixel position, raising `worst`
// to the largest distance in pixels between a position and its ray's projection.
std::vector<cv::Vec2d> undistort(const Camera &cam, const std::vector<cv::Vec2d> &pixels, double &worst)
{
	std::vector<cv::Vec2d> rays;
	if (cam.dist.empty()) {
		for (const cv::Vec2d &p : pixels)
			rays.emplace_back((p[0] - cam.cx) / cam.fx, (p[1] - cam.cy) / cam.fy);
		return rays;
	}

	if (cam.fov) {
		// The FOV lens's inverse is closed (mvod_fov_undistort_radius): exact, no iteration.
		for (const cv::Vec2d &p : pixels) {
			const cv::Vec2d d((p[0] - cam.cx) / cam.fx, (p[1] - cam.cy) / cam.fy);
			const double rd = cv::norm(d), r = mvod_fov_undistort_radius(cam.dist[0], rd);
			rays.push_back(rd > 0 ? d * (r / rd) : d);
			const double back = mvod_fov_distort_radius(cam.dist[0], r) * std::max(cam.fx, cam.fy);
			worst = std::max(worst, std::isfinite(r) ? std::fabs(back - rd * std::max(cam.fx, cam.fy)) : INFINITY);
		}
		return rays;
	}
	const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
	// OpenCV's default of 5 (radial-tangential) or 10 (fisheye) iterations leaves visible errors
	// at the image corners for strong lenses; iterate to convergence instead.
	const cv::TermCriteria converged(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12);
	std::vector<cv::Vec2d> back;
	if (cam.fisheye) {
		cv::fisheye::undistortPoints(pixels, rays, K, cam.dist, cv::noArray(), cv::noArray(), converged);
		cv::fisheye::distortPoints(rays, back, K, cam.dist);
	} else {
		cv::undistortPoints(pixels, rays, K, cam.dist, cv::noArray(), cv::noArray(), converged);
		std::vector<cv::Vec3d> points;
		for (const cv::Vec2d &r : rays)
			points.emplace_back(r[0], r[1], 1.0);
		cv::projectPoints(points, cv::Vec3d(), cv::Vec3d(), K, cam.dist, back);
	}
	for (size_t i = 0; i < pixels.size(); i++) {
		const double e = cv::norm(back[i] - pixels[i]);
		worst = std::isfinite(e) ? std::max(worst, e) : INFINITY;
	}
	return rays;
}

// Bounds in normalised image coordinates of the part of the plane's polygon in front of the
// camera (clipped to z >= kNear, one Sutherland-Hodgman pass) and the least depth in that part;
// false when no part is in front.
bool project_bounds(const Plane &plane, const Pose &pose, cv::Rect2d &bounds, double &nearest)
{
	std::array<cv::Vec3d, 4> c;
	for (size_t i = 0; i < c.size(); i++)
		c[i] = pose.R.t() * (plane.corners[i] - pose.t);

	double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
	nearest = INFINITY;
	const auto add = [&](const cv::Vec3d &q) {
		nearest = std::min(nearest, q[2]);
		x0 = std::min(x0, q[0] / q[2]);
		x1 = std::max(x1, q[0] / q[2]);
		y0 = std::min(y0, q[1] / q[2]);
		y1 = std::max(y1, q[1] / q[2]);
	};
	for (size_t i = 0; i < c.size(); i++) {
		const cv::Vec3d &a = c[i], &b = c[(i + 1) % c.size()];
		if (a[2] >= kNear)
			add(a);
		if ((a[2] >= kNear) != (b[2] >= kNear))
			add(a + (kNear - a[2]) / (b[2] - a[2]) * (b - a));
	}
	if (x0 > x1)
		return false;
	bounds = cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
	return true;
}

} // namespace

Renderer::Renderer(const World &world, const Camera &camera) : world_(world), camera_(camera)
{
	make_tiles();
}

void Renderer::make_tiles()
{
	const int w = camera_.width, h = camera_.height;
	// Tile by tile, pixel by pixel, the sensor positions of the samples.
	std::vector<cv::Vec2d> samples;
	samples.reserve(size_t(w) * size_t(h) * kSamples);
	for (int ty = 0; ty < h; ty += kTile) {
		for (int tx = 0; tx < w; tx += kTile) {
			Tile tile;
			tile.pixels = cv::Rect(tx, ty, std::min(kTile, w - tx), std::min(kTile, h - ty));
			tile.first = samples.size() / kSamples;
			for (int y = ty; y < tile.pixels.br().y; y++)
				for (int x = tx; x < tile.pixels.br().x; x++)
					for (int k = 0; k < kSamples; k++)
						samples.emplace_back(x + (k % kSupersample + 0.5) / kSupersample - 0.5,
								     y + (k / kSupersample + 0.5) / kSupersample - 0.5);
			tiles_.push_back(tile);
		}
	}
	const std::vector<cv::Vec2d> rays = undistort(camera_, samples, worst_ray_error_);

	// Pixel corners give each pixel's extent in normalised coordinates, for texture filtering.
	std::vector<cv::Vec2d> corners;
	corners.reserve(size_t(w + 1) * size_t(h + 1));
	for (int y = 0; y <= h; y++)
		for (int x = 0; x <= w; x++)
			corners.emplace_back(x - 0.5, y - 0.5);
	const std::vector<cv::Vec2d> c = undistort(camera_, corners, worst_ray_error_);
	const auto corner = [&](int x, int y) { return c[size_t(y) * size_t(w + 1) + size_t(x)]; };

	rays_.resize(samples.size() / kSamples);
	for (Tile &tile : tiles_) {
		double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
		size_t i = tile.first;
		for (int y = tile.pixels.y; y < tile.pixels.br().y; y++) {
			for (int x = tile.pixels.x; x < tile.pixels.br().x; x++, i++) {
				PixelRays &p = rays_[i];
				for (int k = 0; k < kSamples; k++) {
					const cv::Vec2d &r = p.sample[k] = rays[i * kSamples + size_t(k)];
					x0 = std::min(x0, r[0]);
					x1 = std::max(x1, r[0]);
					y0 = std::min(y0, r[1]);
					y1 = std::max(y1, r[1]);
				}
				p.dx = 0.5 * ((corner(x + 1, y) - corner(x, y)) + (corner(x + 1, y + 1) - corner(x, y + 1)));
				p.dy = 0.5 * ((corner(x, y + 1) - corner(x, y)) + (corner(x + 1, y + 1) - corner(x + 1, y)));
			}
		}
		tile.rays = cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
	}
}

void Renderer::collect_views(const Pose &pose)
{
	views_.clear();
	for (const Plane &p : world_.planes) {
		if (cv::norm(p.centre - pose.t) - p.radius > kHazeEnd)
			continue;
		View v{&p, p.height.in_camera(pose), p.a.in_camera(pose), p.b.in_camera(pose), p.u.in_camera(pose),
		       p.v.in_camera(pose), {}, 0};
		// The camera sits at the origin of its own frame, so height.h is its height above the plane.
		if (p.one_sided && v.height.h <= 0)
			continue;
		if (project_bounds(p, pose, v.bounds, v.nearest))
			views_.push_back(v);
	}
	// Nearest first, so that a ray can stop looking once the rest are all further than its hit.
	std::stable_sort(views_.begin(), views_.end(), [](const View &a, const View &b) { return a.nearest < b.nearest; });
	for (Tile &tile : tiles_) {
		tile.views.clear();
		for (size_t i = 0; i < views_.size(); i++)
			if (overlaps(tile.rays, views_[i].bounds))
				tile.views.push_back(int(i));
	}
}

void Renderer::render(const Pose &pose, cv::Mat &out)
{
	out.create(camera_.height, camera_.width, CV_32F);
	collect_views(pose);
	// Row y of R turns a camera-frame direction into its world y (down) component.
	const cv::Vec3d world_y(pose.R(1, 0), pose.R(1, 1), pose.R(1, 2));
	cv::parallel_for_(cv::Range(0, int(tiles_.size())), [&](const cv::Range &range) {
		for (int i = range.start; i < range.end; i++)
			render_tile(tiles_[size_t(i)], world_y, out);
	});
}

void Renderer::render_tile(const Tile &tile, const cv::Vec3d &world_y, cv::Mat &out) const
{
	const PixelRays *rays = &rays_[tile.first];
	for (int y = tile.pixels.y; y < tile.pixels.br().y; y++) {
		float *row = out.ptr<float>(y);
		for (int x = tile.pixels.x; x < tile.pixels.br().x; x++)
			row[x] = render_pixel(tile, *rays++, world_y);
	}
}

float Renderer::render_pixel(const Tile &tile, const PixelRays &pixel, const cv::Vec3d &world_y) const
{
	cv::Vec3d rays[kSamples];
	const View *hits[kSamples];
	for (int k = 0; k < kSamples; k++) {
		rays[k] = cv::Vec3d(pixel.sample[k][0], pixel.sample[k][1], 1);
		hits[k] = nearest(tile, rays[k]);
	}

	const cv::Vec3d dx(pixel.dx[0], pixel.dx[1], 0), dy(pixel.dy[0], pixel.dy[1], 0);
	bool done[kSamples] = {};
	float sum = 0;
	for (int k = 0; k < kSamples; k++) {
		if (done[k])
			continue;
		// One texture lookup per surface in the pixel, along the mean of the rays that hit it
		// (which lies on the surface, since the surface is convex), weighted by their number.
		cv::Vec3d mean;
		int count = 0;
		for (int j = k; j < kSamples; j++) {
			if (hits[j] == hits[k]) {
				mean += rays[j];
				count++;
				done[j] = true;
			}
		}
		mean /= count;
		const float sky = sky_grey(-world_y.dot(mean) / cv::norm(mean));
		sum += float(count) * (hits[k] ? shade(*hits[k], mean, dx, dy, sky) : sky);
	}
	return sum / kSamples;
}

// The nearest rectangle the ray (camera frame, z = 1) hits, or null for the sky.
const Renderer::View *Renderer::nearest(const Tile &tile, const cv::Vec3d &ray) const
{
	double depth = INFINITY; // along z, since the ray has z = 1
	const View *hit = nullptr;
	for (int i : tile.views) {
		const View &v = views_[size_t(i)];
		if (v.nearest >= depth)
			break;
		const double t = -v.height.h / v.height.g.dot(ray);
		if (!(t > kNear && t < depth)) // also rejects rays parallel to the plane (inf, nan)
			continue;
		const cv::Vec3d x = t * ray;
		const double a = v.a(x), b = v.b(x);
		if (a >= 0 && a <= v.plane->len_a && b >= 0 && b <= v.plane->len_b && (!v.plane->triangle || a + b <= 1)) {
			depth = t;
			hit = &v;
		}
	}
	return hit;
}

// The textured grey where the ray meets the view's plane, hazed towards the sky behind it. The
// ray differentials (how the ray changes to the next pixel in x and in y) give how the hit
// slides across the plane, and from that the texture footprint to filter over.
float Renderer::shade(const View &view, const cv::Vec3d &ray, const cv::Vec3d &ray_dx, const cv::Vec3d &ray_dy,
		      float sky) const
{
	const cv::Vec3d &n = view.height.g;
	const double along = n.dot(ray), depth = -view.height.h / along;
	const cv::Vec3d x = depth * ray;
	const cv::Vec3d hit_dx = depth * (ray_dx - (n.dot(ray_dx) / along) * ray);
	const cv::Vec3d hit_dy = depth * (ray_dy - (n.dot(ray_dy) / along) * ray);
	const Footprint fp{view.u(x), view.v(x), view.u.g.dot(hit_dx), view.v.g.dot(hit_dx), view.u.g.dot(hit_dy),
			   view.v.g.dot(hit_dy)};
	const Plane &p = *view.plane;
	const float grey = p.gain * world_.textures[size_t(p.texture)].sample(fp) + p.bias;
	return grey + haze(depth * cv::norm(ray)) * (sky - grey);
}

} // namespace synth
