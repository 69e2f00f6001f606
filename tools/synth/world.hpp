// The synthetic world: textured planar rectangles laid out along the camera's path.
#pragma once

#include "texture.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace synth {

// Camera-to-world: X_world = R * X_cam + t. OpenCV axes (x right, y down, z forward).
struct Pose {
	cv::Matx33d R = cv::Matx33d::eye();
	cv::Vec3d t;
};

// An affine function of a point, g . X + h. Every per-plane quantity the renderer needs (signed
// height above the plane, position across the rectangle, texel coordinates) is one of these, so
// moving it into a camera's frame is a single change of variables.
struct Affine {
	cv::Vec3d g;
	double h = 0;

	double operator()(const cv::Vec3d &x) const { return g.dot(x) + h; }
	// The same function of camera coordinates, for a camera at `pose`.
	Affine in_camera(const Pose &pose) const { return {pose.R.t() * g, g.dot(pose.t) + h}; }
};

// A textured rectangle or triangle. A point X lies on it when height(X) == 0, 0 <= a(X) <= len_a
// and 0 <= b(X) <= len_b, and for a triangle also a(X) + b(X) <= 1 (a and b are then barycentric
// coordinates, len_a = len_b = 1; for a rectangle, metres). Its texel coordinates are (u(X), v(X)).
struct Plane {
	Affine height; // signed distance, positive on the visible side
	Affine a, b;
	double len_a, len_b;
	bool triangle;
	Affine u, v;
	bool one_sided; // box faces and the ground are invisible from behind; walls are not
	int texture;    // index into World::textures
	float gain, bias; // per-plane shading: grey = gain * texel + bias
	std::array<cv::Vec3d, 4> corners; // a triangle repeats its last
	cv::Vec3d centre;
	double radius; // of the bounding sphere about centre
};

struct World {
	std::vector<Texture> textures;
	std::vector<Plane> planes;
};

// The line a street follows: a polyline through the camera path (plus run-outs before and after
// it, or closed for loops), parametrised by arc length in metres along its horizontal projection.
class Skeleton {
public:
	// points: at least one; runs of points closer than half a metre collapse to one. An open
	// skeleton runs straight on for a while before its first point and after its last, in the
	// direction of travel there, or along `heading` when the points do not move at all.
	Skeleton(const std::vector<cv::Vec3d> &points, bool closed, const cv::Vec3d &heading);

	double length() const { return s_.back(); }
	bool closed() const { return closed_; }
	cv::Vec3d at(double s) const;   // point at arc length s (wraps when closed, clamps when open)
	cv::Vec3d left(double s) const; // horizontal unit vector to the left of the direction of travel

private:
	std::vector<cv::Vec3d> points_;
	std::vector<double> s_; // cumulative horizontal arc length at each point
	bool closed_;
};

// A street along the skeleton: ground 1.6 m below it (a height field that follows the
// skeleton's height), facades in two rows on each side, boxes and poles at the kerbs. Anything that would come
// within reach of a camera position is left out, so the camera never drives through geometry.
// Deterministic in (skeleton, cameras, seed). A stretch of street depends on the skeleton up to
// it, not beyond, except where later parts of the path come near it.
World build_street(const Skeleton &skeleton, const std::vector<cv::Vec3d> &cameras, uint64_t seed);

// A calibration target for mvod-synth --board: `face` (8-bit grey, the pattern with its quiet
// zone, as mvod_board_draw makes it) on the plane z = 0 of the board frame (x right, y down, z
// into the board; include/mvod/board.h), its top-left texel corner at (-margin_m, -margin_m),
// texel_m metres per texel, in front of a dim, low-contrast textured wall. Printed blacks and
// whites are 20 and 224 rather than 0 and 255, so that noise is not clipped. Deterministic in
// (face, seed).
World build_board_scene(const cv::Mat &face, double margin_m, double texel_m, uint64_t seed);

// Height of the camera above the ground it moves over, in metres (the ground is +y of it).
constexpr double kCameraHeight = 1.6;

// Well-mixed seed for an independent random stream (splitmix64).
uint64_t stream_seed(uint64_t seed, uint64_t stream);

} // namespace synth
