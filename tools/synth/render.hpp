// Ray casting the world through a (possibly distorted) camera.
#pragma once

#include "world.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace synth {

// Intrinsics in OpenCV's conventions: pixel centres at integer coordinates, distortion
// coefficients in OpenCV order.
struct Camera {
	int width = 0, height = 0;
	double fx = 0, fy = 0, cx = 0, cy = 0;
	bool fisheye = false;     // Kannala-Brandt k1..k4 (cv::fisheye) instead of radial-tangential
	bool fov = false;         // the FOV lens of DSO and PTAM, dist = {w} (radians), mvod's closed form
	std::vector<double> dist; // empty: an ideal pinhole
};

// Renders grey images of a world. Every sample is a ray cast through the undistorted normalised
// coordinates of its position on the sensor, so distortion is exact rather than resampled.
// Like multisample anti-aliasing, a 2x2 grid of rays per pixel decides which surfaces cover how
// much of it (smooth edges), and each covering surface is textured once, filtered over the
// pixel's footprint on it (no shimmer in distant texture from frame to frame).
class Renderer {
public:
	Renderer(const World &world, const Camera &camera); // world is borrowed for the lifetime
	Renderer(const Renderer &) = delete;
	Renderer &operator=(const Renderer &) = delete;

	// Largest distance in pixels between a sample position and the projection of its ray: near
	// zero unless the distortion folds over inside the image, so that some pixels see nothing.
	double worst_ray_error() const { return worst_ray_error_; }

	// The view from `pose` (camera-to-world), as CV_32F grey levels (0..255, unclamped).
	void render(const Pose &pose, cv::Mat &out);

private:
	static constexpr int kSupersample = 2;                        // rays per pixel along each axis
	static constexpr int kSamples = kSupersample * kSupersample; // rays per pixel

	// A plane moved into the current camera's frame, with the bounds of its projection in
	// normalised image coordinates and the depth of its nearest point in view.
	struct View {
		const Plane *plane;
		Affine height, a, b, u, v;
		cv::Rect2d bounds;
		double nearest;
	};
	// The rays of one pixel in normalised coordinates (z = 1): its samples, and how the ray
	// changes across the pixel in x and in y.
	struct PixelRays {
		cv::Vec2d sample[kSamples];
		cv::Vec2d dx, dy;
	};
	// A square of pixels with the bounds of its rays and the views that may cover it, nearest
	// first. Its pixels' rays are stored together, row by row, from `first`.
	struct Tile {
		cv::Rect pixels;
		size_t first;
		cv::Rect2d rays;
		std::vector<int> views;
	};

	void make_tiles();
	void collect_views(const Pose &pose);
	void render_tile(const Tile &tile, const cv::Vec3d &world_y, cv::Mat &out) const;
	float render_pixel(const Tile &tile, const PixelRays &rays, const cv::Vec3d &world_y) const;
	const View *nearest(const Tile &tile, const cv::Vec3d &ray) const;
	float shade(const View &view, const cv::Vec3d &ray, const cv::Vec3d &ray_dx, const cv::Vec3d &ray_dy,
		    float sky) const;

	const World &world_;
	Camera camera_;
	std::vector<PixelRays> rays_; // tile by tile
	double worst_ray_error_ = 0;
	std::vector<Tile> tiles_;
	std::vector<View> views_;
};

} // namespace synth
