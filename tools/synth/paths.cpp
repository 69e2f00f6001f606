#include "paths.hpp"

#include "failure.hpp"

extern "C" {
#include "mvod/traj.h"
}

#include <cmath>
#include <cstring>
#include <functional>
#include <memory>

namespace synth {

namespace {

constexpr double kLoopRadius = 6; // metres, for circle and figure8
constexpr double kDegree = CV_PI / 180;

// Curvature in 1/m as a function of arc length; positive turns left.
using Curvature = std::function<double(double)>;

// A vehicle on flat ground: position (x, z) and yaw, the heading (sin yaw, 0, cos yaw). With y
// pointing down, positive yaw turns right.
struct Planar {
	double x = 0, z = 0, yaw = 0;
};

cv::Matx33d rot_y(double a)
{
	return {std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a)};
}

cv::Matx33d rot_x(double a)
{
	return {1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a)};
}

Pose planar_pose(const Planar &p)
{
	return {rot_y(p.yaw), cv::Vec3d(p.x, 0, p.z)};
}

// Drives along the curvature profile from the origin heading +z and reports the state at each
// of the ascending arc lengths in `at`. Midpoint steps of 5 mm: the result is a smooth curve
// whatever its accuracy, and it is the ground truth because it is what gets rendered.
std::vector<Planar> drive(const Curvature &curvature, const std::vector<double> &at)
{
	constexpr double kStep = 0.005;
	std::vector<Planar> out;
	Planar p;
	double s = 0;
	for (double target : at) {
		while (s < target) {
			const double h = std::min(kStep, target - s);
			const double turn = h * curvature(s + 0.5 * h);
			const double heading = p.yaw - 0.5 * turn;
			p.x += h * std::sin(heading);
			p.z += h * std::cos(heading);
			p.yaw -= turn;
			s += h;
		}
		out.push_back(p);
	}
	return out;
}

std::vector<double> frame_times(int frames, double fps)
{
	std::vector<double> t;
	for (int i = 0; i < frames; i++)
		t.push_back(i / fps);
	return t;
}

std::vector<cv::Vec3d> positions(const std::vector<Pose> &poses)
{
	std::vector<cv::Vec3d> out;
	for (const Pose &p : poses)
		out.push_back(p.t);
	return out;
}

// A path driven along a curvature profile. lap > 0 marks a loop of that length (metres): the
// street then follows one whole lap.
Trajectory along_curve(const Curvature &curvature, double lap, int frames, double fps, double speed)
{
	Trajectory tr;
	tr.times = frame_times(frames, fps);
	std::vector<double> s;
	for (double t : tr.times)
		s.push_back(speed * t);
	for (const Planar &p : drive(curvature, s))
		tr.poses.push_back(planar_pose(p));

	if (lap > 0) {
		std::vector<double> around;
		for (double x = 0; x < lap; x += 0.5)
			around.push_back(x);
		for (const Planar &p : drive(curvature, around))
			tr.skeleton.push_back(planar_pose(p).t);
		tr.closed = true;
	} else {
		tr.skeleton = positions(tr.poses);
	}
	return tr;
}

// Straight ahead, with a slow sway a hand-held or vehicle camera would have: +-3 cm sideways,
// +-0.5 deg yaw, +-0.3 deg pitch, at unrelated periods (all zero at t = 0).
Trajectory forward(int frames, double fps, double speed)
{
	Trajectory tr = along_curve([](double) { return 0.0; }, 0, frames, fps, speed);
	for (size_t i = 0; i < tr.poses.size(); i++) {
		const double t = tr.times[i];
		Pose &p = tr.poses[i];
		p.t[0] += 0.03 * std::sin(2 * CV_PI * t / 3.7);
		p.R = rot_y(0.5 * kDegree * std::sin(2 * CV_PI * t / 2.9)) * rot_x(0.3 * kDegree * std::sin(2 * CV_PI * t / 2.3));
	}
	tr.skeleton = positions(tr.poses);
	return tr;
}

// Straight for the first 30% of the distance, a 90 deg left turn over the next 40% whose
// curvature rises and falls smoothly (no jerk at either end), then straight again.
Trajectory turn(int frames, double fps, double speed)
{
	const double length = speed * (frames - 1) / fps;
	const double start = 0.3 * length, span = 0.4 * length;
	const Curvature bump = [=](double s) {
		if (s < start || s > start + span)
			return 0.0;
		return (CV_PI / 2) / span * (1 - std::cos(2 * CV_PI * (s - start) / span));
	};
	return along_curve(bump, 0, frames, fps, speed);
}

// Stop and go along a gentle left curve (radius 40 m): speeding up from 0.5 to 1.5 times
// `speed` over the first quarter of the time, braking to a standstill by 40 %, standing until
// 50 %, pulling away to `speed` by 65 % and holding it. No step length repeats the one before,
// so a VO that carried its last step forward (constant speed) drifts in scale.
Trajectory stop_go(int frames, double fps, double speed)
{
	const auto v = [](double u) { // speed as a fraction of `speed`, u = fraction of the time
		if (u < 0.25)
			return 0.5 + 4 * u;
		if (u < 0.4)
			return 1.5 * (0.4 - u) / 0.15;
		if (u < 0.5)
			return 0.0;
		return u < 0.65 ? (u - 0.5) / 0.15 : 1.0;
	};
	Trajectory tr;
	tr.times = frame_times(frames, fps);
	const double duration = std::max(tr.times.back(), 1e-9);
	// Arc length by the midpoint rule over 100 sub-steps a frame: exact for the linear pieces
	// but for the sub-step holding a corner of the profile, which is the ground truth anyway.
	std::vector<double> s;
	double arc = 0, t = 0;
	for (double target : tr.times) {
		for (const double h = (target - t) / 100; t < target - 0.5 * h; t += h)
			arc += h * speed * v((t + 0.5 * h) / duration);
		t = target;
		s.push_back(arc);
	}
	for (const Planar &p : drive([](double) { return 1 / 40.0; }, s))
		tr.poses.push_back(planar_pose(p));
	tr.skeleton = positions(tr.poses);
	return tr;
}

Trajectory circle(int frames, double fps, double speed)
{
	return along_curve([](double) { return 1 / kLoopRadius; }, 2 * CV_PI * kLoopRadius, frames, fps, speed);
}

// A lap of a left circle, then one of a right circle: the two touch at the start.
Trajectory figure8(int frames, double fps, double speed)
{
	const double lap = 2 * CV_PI * kLoopRadius;
	const Curvature eight = [=](double s) { return std::fmod(s, 2 * lap) < lap ? 1 / kLoopRadius : -1 / kLoopRadius; };
	return along_curve(eight, 2 * lap, frames, fps, speed);
}

// Yaw swinging +-30 deg, left first, over a 6 s period, about the camera centre: a pure
// rotation, the degenerate case for the essential matrix.
Trajectory rotate_in_place(int frames, double fps, double)
{
	Trajectory tr;
	tr.times = frame_times(frames, fps);
	for (double t : tr.times)
		tr.poses.push_back({rot_y(-30 * kDegree * std::sin(2 * CV_PI * t / 6)), cv::Vec3d()});
	tr.skeleton = positions(tr.poses);
	return tr;
}

Trajectory still(int frames, double fps, double)
{
	Trajectory tr;
	tr.times = frame_times(frames, fps);
	tr.poses.assign(size_t(frames), Pose());
	tr.skeleton = positions(tr.poses);
	return tr;
}

using PathFunction = Trajectory (*)(int frames, double fps, double speed);
const std::pair<const char *, PathFunction> kBuiltins[] = {
	{"forward", forward}, {"turn", turn}, {"circle", circle}, {"figure8", figure8},
	{"rotate-in-place", rotate_in_place}, {"static", still}, {"stop-go", stop_go},
};

// Files round their rotations (KITTI to 7 digits); the nearest true rotation is rendered and
// written back, so that the image, gt.kitti and gt.tum all agree.
Pose from_mvod(const mvod_pose &p)
{
	const cv::SVD svd(cv::Mat(cv::Matx33d(p.R)), cv::SVD::FULL_UV);
	Pose out;
	out.R = cv::Matx33d(cv::Mat(svd.u * svd.vt));
	out.t = cv::Vec3d(p.t[0], p.t[1], p.t[2]);
	return out;
}

} // namespace

std::string builtin_path_names()
{
	std::string names;
	for (const auto &b : kBuiltins)
		names += (names.empty() ? "" : ", ") + std::string(b.first);
	return names;
}

bool is_builtin_path(const std::string &name)
{
	for (const auto &b : kBuiltins)
		if (name == b.first)
			return true;
	return false;
}

Trajectory builtin_path(const std::string &name, int frames, double fps, double speed)
{
	for (const auto &b : kBuiltins)
		if (name == b.first)
			return b.second(frames, fps, speed);
	throw Failure(kExitUsage, "unknown path '" + name + "' (built-ins: " + builtin_path_names() + ")");
}

Trajectory load_path(const std::string &file, int frames, double fps)
{
	mvod_traj traj{};
	char err[256] = "";
	const int rc = mvod_traj_load(file.c_str(), &traj, err, sizeof err);
	if (rc < 0) // the reason names the file
		throw Failure(kExitFailure, std::string("--path: ") + (err[0] ? err : file + ": " + std::strerror(-rc)));
	const std::unique_ptr<mvod_traj, void (*)(mvod_traj *)> owner(&traj, mvod_traj_free);
	if (traj.n == 0)
		throw Failure(kExitFailure, "pose file " + file + " holds no poses");
	if (frames > traj.n)
		throw Failure(kExitUsage, "--frames " + std::to_string(frames) + ": " + file + " holds only " +
						  std::to_string(traj.n) + " poses");

	Trajectory tr;
	const int n = frames > 0 ? frames : traj.n;
	for (int i = 0; i < n; i++) {
		tr.times.push_back(traj.format == MVOD_TRAJ_TUM ? traj.t[i] : i / fps);
		tr.poses.push_back(from_mvod(traj.pose[i]));
	}
	tr.skeleton = positions(tr.poses);
	return tr;
}

} // namespace synth
