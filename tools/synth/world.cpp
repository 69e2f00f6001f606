#include "world.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace synth {

namespace {

// Street before and after an open path, so the first frames look down a street rather than
// at its end and the last frames still see one ahead (it fades into the haze at 100 m).
constexpr double kRunBehind = 40, kRunAhead = 120;

// Texture 0 is the ground; the others form a pool shared by walls and boxes, each plane
// starting at its own random place in its texture.
constexpr int kGroundTexture = 0, kPoolTextures = 16;
constexpr int kGroundSize = 2048, kPoolSize = 1024;
// 1.2 cm texels: about one pixel where the ground enters the bottom of a 640x480 view with the
// default intrinsics; the texture repeats every 24.6 m, beyond where it can be matched.
constexpr double kGroundTexel = 0.012;

// The ground is a triangulated height field on a grid of 16 m cells, everywhere within 48 m of
// the skeleton: each grid point lies 1.6 m below the nearest point of the skeleton. On flat
// paths it is one plane; on hilly ones it bends without gaps or overlaps.
constexpr double kGroundCell = 16, kGroundReach = 48;

const cv::Vec3d kUp(0, -1, 0);

struct RowStyle {
	double offset[2], height[2], length[2]; // metres: ranges drawn uniformly
	double gap;                             // probability that a stretch stays empty
	double reach;                           // nearest a camera may be to the facade
};
// A broken row of houses close to the street and a continuous taller one behind it, so gaps
// show more depth rather than the end of the world.
const RowStyle kNearRow = {{6, 9}, {4, 12}, {6, 14}, 0.2, 4.0};
const RowStyle kFarRow = {{13, 18}, {8, 20}, {8, 20}, 0.0, 6.0};

cv::Vec3d horizontal(cv::Vec3d v)
{
	v[1] = 0;
	const double n = cv::norm(v);
	return n > 1e-12 ? v / n : cv::Vec3d();
}

double horizontal_distance(const cv::Vec3d &a, const cv::Vec3d &b)
{
	return std::hypot(a[0] - b[0], a[2] - b[2]);
}

// Horizontal direction from `from` to the first of [first, last) at least 3 m away from it, or
// `fallback` when none is.
template <typename It> cv::Vec3d travel(const cv::Vec3d &from, It first, It last, const cv::Vec3d &fallback)
{
	for (; first != last; ++first)
		if (horizontal_distance(from, *first) >= 3.0)
			return horizontal(*first - from);
	return fallback;
}

// Horizontal distance from the segment p0-p1 to the nearest camera position.
double clearance(const cv::Vec3d &p0, const cv::Vec3d &p1, const std::vector<cv::Vec3d> &cameras)
{
	const cv::Vec2d a(p0[0], p0[2]), ab = cv::Vec2d(p1[0], p1[2]) - a;
	const double ab2 = std::max(ab.dot(ab), 1e-12);
	double best = INFINITY;
	for (const cv::Vec3d &c : cameras) {
		const cv::Vec2d ac = cv::Vec2d(c[0], c[2]) - a;
		const double k = std::clamp(ac.dot(ab) / ab2, 0.0, 1.0);
		best = std::min(best, cv::norm(ac - k * ab));
	}
	return best;
}

// A rectangle with corner `origin`, spanning len_a along the unit vector ea and len_b along
// the orthogonal unit vector eb, facing the side `front` points to.
Plane rectangle(const cv::Vec3d &origin, const cv::Vec3d &ea, double len_a, const cv::Vec3d &eb, double len_b,
		const cv::Vec3d &front, bool one_sided)
{
	cv::Vec3d n = cv::normalize(ea.cross(eb));
	if (n.dot(front) < 0)
		n = -n;
	Plane p{};
	p.height = {n, -n.dot(origin)};
	p.a = {ea, -ea.dot(origin)};
	p.b = {eb, -eb.dot(origin)};
	p.len_a = len_a;
	p.len_b = len_b;
	p.one_sided = one_sided;
	p.corners = {origin, origin + len_a * ea, origin + len_a * ea + len_b * eb, origin + len_b * eb};
	p.centre = origin + 0.5 * (len_a * ea + len_b * eb);
	p.radius = 0.5 * std::hypot(len_a, len_b);
	return p;
}

// The triangle p0 p1 p2, facing the side `front` points to.
Plane triangle(const cv::Vec3d &p0, const cv::Vec3d &p1, const cv::Vec3d &p2, const cv::Vec3d &front, bool one_sided)
{
	const cv::Vec3d e1 = p1 - p0, e2 = p2 - p0;
	cv::Vec3d n = cv::normalize(e1.cross(e2));
	if (n.dot(front) < 0)
		n = -n;
	// The dual basis of (e1, e2) in their plane (d1.e1 = 1, d1.e2 = 0, ...) reads off the
	// barycentric coordinates of p1 and p2.
	const double g11 = e1.dot(e1), g12 = e1.dot(e2), g22 = e2.dot(e2), det = g11 * g22 - g12 * g12;
	const cv::Vec3d d1 = (g22 * e1 - g12 * e2) / det, d2 = (g11 * e2 - g12 * e1) / det;
	Plane p{};
	p.height = {n, -n.dot(p0)};
	p.a = {d1, -d1.dot(p0)};
	p.b = {d2, -d2.dot(p0)};
	p.len_a = p.len_b = 1;
	p.triangle = true;
	p.one_sided = one_sided;
	p.corners = {p0, p1, p2, p2};
	p.centre = (p0 + p1 + p2) / 3;
	p.radius = std::max({cv::norm(p0 - p.centre), cv::norm(p1 - p.centre), cv::norm(p2 - p.centre)});
	return p;
}

// Pins a random window of a pool texture to the rectangle at `texel` metres per texel, with
// its own brightness and contrast.
void paint(Plane &p, double texel, cv::RNG &rng)
{
	p.texture = 1 + rng.uniform(0, kPoolTextures);
	p.u = {p.a.g / texel, p.a.h / texel + rng.uniform(0.0, double(kPoolSize))};
	p.v = {p.b.g / texel, p.b.h / texel + rng.uniform(0.0, double(kPoolSize))};
	p.gain = float(rng.uniform(0.7, 1.15));
	p.bias = float(rng.uniform(-15.0, 15.0));
}

// Ground texture coordinates come from world x and z rather than from each triangle, so the
// texture runs on across the height field without seams.
void paint_ground(Plane &p)
{
	p.texture = kGroundTexture;
	p.u = {cv::Vec3d(1 / kGroundTexel, 0, 0), 0};
	p.v = {cv::Vec3d(0, 0, 1 / kGroundTexel), 0};
	p.gain = 1;
	p.bias = 0;
}

cv::Vec3d ground_below(const cv::Vec3d &p)
{
	return p + cv::Vec3d(0, kCameraHeight, 0);
}

void add_ground(World &world, const Skeleton &sk)
{
	std::vector<cv::Vec3d> path;
	for (double s = 0; s <= sk.length(); s += 2)
		path.push_back(sk.at(s));

	using Cell = std::pair<int, int>; // grid indices along x and z
	const auto index = [](double metres) { return int(std::floor(metres / kGroundCell)); };
	const int reach = int(std::ceil(kGroundReach / kGroundCell));
	std::set<Cell> cells;
	for (const cv::Vec3d &p : path)
		for (int i = index(p[0]) - reach; i <= index(p[0]) + reach; i++)
			for (int j = index(p[2]) - reach; j <= index(p[2]) + reach; j++)
				cells.insert({i, j});

	std::map<Cell, cv::Vec3d> points;
	const auto point = [&](int i, int j) {
		auto it = points.find({i, j});
		if (it == points.end()) {
			cv::Vec3d q(i * kGroundCell, 0, j * kGroundCell);
			const auto closest = std::min_element(path.begin(), path.end(), [&](const cv::Vec3d &a, const cv::Vec3d &b) {
				return horizontal_distance(a, q) < horizontal_distance(b, q);
			});
			q[1] = ground_below(*closest)[1];
			it = points.emplace(Cell(i, j), q).first;
		}
		return it->second;
	};
	for (const Cell &c : cells) {
		const cv::Vec3d p00 = point(c.first, c.second), p10 = point(c.first + 1, c.second);
		const cv::Vec3d p01 = point(c.first, c.second + 1), p11 = point(c.first + 1, c.second + 1);
		for (Plane p : {triangle(p00, p10, p11, kUp, true), triangle(p00, p11, p01, kUp, true)}) {
			paint_ground(p);
			world.planes.push_back(p);
		}
	}
}

// One row of facades on one side (+1 left, -1 right) of the skeleton. Every stretch draws the
// same random numbers whether or not it is kept, so the layout of one stretch never depends
// on where the rest of the path goes.
void add_facades(World &world, const Skeleton &sk, const std::vector<cv::Vec3d> &cameras, int side,
		 const RowStyle &style, cv::RNG &rng)
{
	for (double s0 = 0; s0 < sk.length();) {
		const double s1 = std::min(s0 + rng.uniform(style.length[0], style.length[1]), sk.length());
		const bool gap = rng.uniform(0.0, 1.0) < style.gap;
		const double offset = rng.uniform(style.offset[0], style.offset[1]);
		const double height = rng.uniform(style.height[0], style.height[1]);
		const cv::Vec3d p0 = sk.at(s0) + side * offset * sk.left(s0);
		const cv::Vec3d p1 = sk.at(s1) + side * offset * sk.left(s1);
		const double length = horizontal_distance(p0, p1);
		const cv::Vec3d along = horizontal(p1 - p0);
		// Sunk a metre below the lower end so that sloping ground never shows under it.
		const double bottom = std::max(p0[1], p1[1]) + kCameraHeight + 1.0;
		const double top = std::min(p0[1], p1[1]) + kCameraHeight - height;
		Plane p = rectangle(cv::Vec3d(p0[0], bottom, p0[2]), along, length, kUp, bottom - top,
				    -side * sk.left(s0), false);
		paint(p, rng.uniform(0.012, 0.02), rng);
		// On the inside of a tight bend the offset ends cross over: no facade fits there.
		const bool fits = length > 1.0 && along.dot(horizontal(sk.at(s1) - sk.at(s0))) > 0;
		if (!gap && fits && clearance(p0, p1, cameras) >= style.reach)
			world.planes.push_back(p);
		s0 = s1;
	}
}

// The four sides and the top of a box standing on the ground at `base` (sunk a little).
std::vector<Plane> box(const cv::Vec3d &base, double yaw, double width, double depth, double height, cv::RNG &rng)
{
	const cv::Vec3d e1(std::cos(yaw), 0, std::sin(yaw)), e2(-std::sin(yaw), 0, std::cos(yaw));
	const cv::Vec3d bottom = base + cv::Vec3d(0, 0.3, 0);
	const double tall = height + 0.3;
	std::vector<Plane> faces;
	for (int k = 0; k < 4; k++) {
		const bool across = k < 2; // faces with normal +-e1 span the depth
		const cv::Vec3d normal = (k % 2 ? -1.0 : 1.0) * (across ? e1 : e2);
		const cv::Vec3d tangent = across ? e2 : e1;
		const double half = 0.5 * (across ? width : depth), span = across ? depth : width;
		faces.push_back(rectangle(bottom + half * normal - 0.5 * span * tangent, tangent, span, kUp, tall, normal,
					  true));
	}
	faces.push_back(rectangle(bottom + tall * kUp - 0.5 * width * e1 - 0.5 * depth * e2, e1, width, e2, depth, kUp,
				  true));
	for (Plane &f : faces)
		paint(f, rng.uniform(0.005, 0.01), rng);
	return faces;
}

// Boxes and poles at the kerb on one side (+1 left, -1 right).
void add_boxes(World &world, const Skeleton &sk, const std::vector<cv::Vec3d> &cameras, int side, cv::RNG &rng)
{
	for (double s = rng.uniform(0.0, 3.0); s < sk.length(); s += rng.uniform(2.0, 6.0)) {
		const double offset = rng.uniform(2.5, 5.0), yaw = rng.uniform(0.0, CV_PI);
		const bool pole = rng.uniform(0.0, 1.0) < 0.15;
		const double width = pole ? rng.uniform(0.15, 0.3) : rng.uniform(0.4, 1.6);
		const double depth = pole ? width : rng.uniform(0.4, 1.6);
		const double height = pole ? rng.uniform(2.5, 5.0) : rng.uniform(0.3, 2.5);
		const cv::Vec3d centre = sk.at(s) + side * offset * sk.left(s);
		const std::vector<Plane> faces = box(ground_below(centre), yaw, width, depth, height, rng);
		if (clearance(centre, centre, cameras) >= 0.5 * std::hypot(width, depth) + 1.5)
			world.planes.insert(world.planes.end(), faces.begin(), faces.end());
	}
}

std::vector<Texture> make_textures(uint64_t seed)
{
	std::vector<cv::Mat> bases(1 + kPoolTextures);
	cv::parallel_for_(cv::Range(0, int(bases.size())), [&](const cv::Range &r) {
		for (int i = r.start; i < r.end; i++)
			bases[i] = generate_texture(i == kGroundTexture ? kGroundSize : kPoolSize, stream_seed(seed, i));
	});
	return {bases.begin(), bases.end()};
}

} // namespace

uint64_t stream_seed(uint64_t seed, uint64_t stream)
{
	uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
	return z ^ (z >> 31);
}

Skeleton::Skeleton(const std::vector<cv::Vec3d> &points, bool closed, const cv::Vec3d &heading) : closed_(closed)
{
	CV_Assert(!points.empty());
	for (const cv::Vec3d &p : points)
		if (points_.empty() || horizontal_distance(points_.back(), p) >= 0.5)
			points_.push_back(p);
	if (closed_) {
		CV_Assert(points_.size() >= 3);
		points_.push_back(points_.front());
	} else {
		const cv::Vec3d first = points_.front(), last = points_.back();
		const cv::Vec3d start = travel(first, points_.begin(), points_.end(), heading);
		const cv::Vec3d end = -travel(last, points_.rbegin(), points_.rend(), -heading);
		points_.insert(points_.begin(), first - kRunBehind * start);
		points_.push_back(last + kRunAhead * end);
	}
	s_.push_back(0);
	for (size_t i = 1; i < points_.size(); i++)
		s_.push_back(s_.back() + horizontal_distance(points_[i - 1], points_[i]));
}

cv::Vec3d Skeleton::at(double s) const
{
	const double len = length();
	s = closed_ ? s - len * std::floor(s / len) : std::clamp(s, 0.0, len);
	const size_t i = std::clamp<size_t>(size_t(std::upper_bound(s_.begin(), s_.end(), s) - s_.begin()), 1,
					    s_.size() - 1);
	const double w = (s - s_[i - 1]) / (s_[i] - s_[i - 1]);
	return points_[i - 1] + w * (points_[i] - points_[i - 1]);
}

cv::Vec3d Skeleton::left(double s) const
{
	// Heading +z has its left at -x (x right, y down): a quarter turn about y.
	const cv::Vec3d d = horizontal(at(s + 2) - at(s - 2));
	return {-d[2], 0, d[0]};
}

World build_board_scene(const cv::Mat &face, double margin_m, double texel_m, uint64_t seed)
{
	// Textures are square powers of two that wrap: pad the face with its own quiet zone, so
	// filtering across the board's edge sees quiet zone rather than the far side of the pattern.
	int side = 1;
	while (side < std::max(face.cols, face.rows))
		side *= 2;
	cv::Mat square(side, side, CV_8UC1, cv::Scalar(face.at<uint8_t>(0, 0)));
	face.copyTo(square(cv::Rect(0, 0, face.cols, face.rows)));

	World world;
	world.textures.emplace_back(square);
	world.textures.emplace_back(generate_texture(kPoolSize, stream_seed(seed, 1)));

	const double w = face.cols * texel_m, h = face.rows * texel_m;
	const cv::Vec3d x(1, 0, 0), y(0, 1, 0), towards(0, 0, -1);
	Plane board = rectangle(cv::Vec3d(-margin_m, -margin_m, 0), x, w, y, h, towards, true);
	board.texture = 0;
	board.u = {board.a.g / texel_m, board.a.h / texel_m};
	board.v = {board.b.g / texel_m, board.b.h / texel_m};
	board.gain = 204.0f / 255.0f;
	board.bias = 20;
	world.planes.push_back(board);

	// A wall one board-width behind, wide enough to fill every view of the board.
	const double reach = 20 * std::max(w, h), wall_texel = std::max(w, h) / 256;
	Plane wall = rectangle(cv::Vec3d(-reach, -reach, std::max(w, h)), x, 2 * reach, y, 2 * reach, towards, true);
	wall.texture = 1;
	wall.u = {wall.a.g / wall_texel, wall.a.h / wall_texel};
	wall.v = {wall.b.g / wall_texel, wall.b.h / wall_texel};
	wall.gain = 0.3f;
	wall.bias = 70;
	world.planes.push_back(wall);
	return world;
}

World build_street(const Skeleton &skeleton, const std::vector<cv::Vec3d> &cameras, uint64_t seed)
{
	World world;
	world.textures = make_textures(seed);
	add_ground(world, skeleton);
	uint64_t stream = 1000;
	for (int side : {1, -1}) {
		cv::RNG near_rng(stream_seed(seed, stream++)), far_rng(stream_seed(seed, stream++));
		cv::RNG box_rng(stream_seed(seed, stream++));
		add_facades(world, skeleton, cameras, side, kNearRow, near_rng);
		add_facades(world, skeleton, cameras, side, kFarRow, far_rng);
		add_boxes(world, skeleton, cameras, side, box_rng);
	}
	return world;
}

} // namespace synth
