#include "board.hpp"

#include "failure.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>

namespace synth {

namespace {

constexpr double kDeg = M_PI / 180;
constexpr double kMaxTilt = 50 * kDeg, kMaxRoll = 45 * kDeg, kMaxObliquity = 60 * kDeg;
constexpr double kMinSpan = 0.3, kMaxSpan = 0.6; // pattern width over image width
constexpr double kEdge = 8;                       // pixels between pattern and image border
constexpr int kGrid = 3;                          // board centres over kGrid x kGrid cells
constexpr int kTries = 1000;

std::vector<cv::Point2d> project(const std::vector<cv::Point3d> &points, const Camera &cam, const BoardPose &pose)
{
	const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
	std::vector<cv::Point2d> px;
	if (cam.fisheye)
		cv::fisheye::projectPoints(points, px, pose.rvec, pose.t, K, cam.dist);
	else
		cv::projectPoints(points, pose.rvec, pose.t, K, cam.dist, px);
	return px;
}

// The pattern's outer corners, then its interior ones: all must be in view.
std::vector<cv::Point3d> outline_and_corners(const mvod_board &board)
{
	int across, down;
	mvod_board_squares(&board, &across, &down);
	const double w = across * board.square_m, h = down * board.square_m;
	std::vector<cv::Point3d> points = {{0, 0, 0}, {w, 0, 0}, {w, h, 0}, {0, h, 0}};
	for (int i = 0; i < mvod_board_corner_count(&board); i++) {
		double xyz[3];
		mvod_board_corner(&board, i, xyz);
		points.emplace_back(xyz[0], xyz[1], xyz[2]);
	}
	return points;
}

cv::Matx33d rotation(double about_x, double about_y, double in_plane)
{
	const double cx = std::cos(about_x), sx = std::sin(about_x), cy = std::cos(about_y), sy = std::sin(about_y);
	const double cz = std::cos(in_plane), sz = std::sin(in_plane);
	const cv::Matx33d Rx(1, 0, 0, 0, cx, -sx, 0, sx, cx), Ry(cy, 0, sy, 0, 1, 0, -sy, 0, cy);
	const cv::Matx33d Rz(cz, -sz, 0, sz, cz, 0, 0, 0, 1);
	return Rx * Ry * Rz;
}

// One random pose with the board centre near image position (gx, gy) (fractions of the size).
BoardPose random_pose(const mvod_board &board, const Camera &cam, double gx, double gy, cv::RNG &rng)
{
	int across, down;
	mvod_board_squares(&board, &across, &down);
	const cv::Vec3d centre(across * board.square_m / 2, down * board.square_m / 2, 0);
	// One draw per statement: the order of evaluation of arguments is unspecified.
	const double span = rng.uniform(kMinSpan, kMaxSpan);
	const double ax = rng.uniform(-kMaxTilt, kMaxTilt);
	const double ay = rng.uniform(-kMaxTilt, kMaxTilt);
	const double az = rng.uniform(-kMaxRoll, kMaxRoll);
	const double depth = cam.fx * 2 * centre[0] / (span * cam.width);
	const cv::Vec3d at(depth * (gx * cam.width - cam.cx) / cam.fx, depth * (gy * cam.height - cam.cy) / cam.fy, depth);
	const cv::Matx33d R = rotation(ax, ay, az);
	BoardPose pose;
	cv::Rodrigues(R, pose.rvec);
	pose.t = at - R * centre;
	return pose;
}

bool acceptable(const BoardPose &pose, const std::vector<cv::Point3d> &points, const Camera &cam)
{
	cv::Matx33d R;
	cv::Rodrigues(pose.rvec, R);
	const cv::Vec3d normal(R(0, 2), R(1, 2), R(2, 2));
	const cv::Vec3d centre = R * (0.5 * cv::Vec3d(points[2].x, points[2].y, 0)) + pose.t; // points[2]: far corner
	if (normal.dot(centre) < std::cos(kMaxObliquity) * cv::norm(centre))
		return false;
	for (const cv::Point2d &p : project(points, cam, pose))
		if (!(p.x >= kEdge && p.y >= kEdge && p.x <= cam.width - 1 - kEdge && p.y <= cam.height - 1 - kEdge))
			return false;
	return true;
}

} // namespace

Pose BoardPose::camera_to_board() const
{
	cv::Matx33d R;
	cv::Rodrigues(rvec, R);
	Pose p;
	p.R = R.t();
	p.t = -(R.t() * t);
	return p;
}

std::vector<cv::Point2d> project_corners(const mvod_board &board, const Camera &cam, const BoardPose &pose)
{
	std::vector<cv::Point3d> points = outline_and_corners(board);
	points.erase(points.begin(), points.begin() + 4);
	return project(points, cam, pose);
}

std::vector<BoardPose> board_poses(const mvod_board &board, const Camera &cam, int views, uint64_t seed)
{
	const std::vector<cv::Point3d> points = outline_and_corners(board);
	cv::RNG rng(stream_seed(seed, 5000));
	std::vector<BoardPose> poses;
	for (int i = 0; i < views; i++) {
		const int cell = i % (kGrid * kGrid);
		const double jx = rng.uniform(-0.5, 0.5), jy = rng.uniform(-0.5, 0.5);
		const double gx = (cell % kGrid + 0.5 + 0.5 * jx) / kGrid, gy = (cell / kGrid + 0.5 + 0.5 * jy) / kGrid;
		int tries = 0;
		BoardPose pose;
		do {
			if (++tries > kTries)
				throw Failure(kExitUsage, "no view of the whole board fits in the image near (" +
								  std::to_string(int(gx * cam.width)) + ", " +
								  std::to_string(int(gy * cam.height)) +
								  "): use a larger image or a weaker lens");
			// Where the board cannot reach the cell's position, move it towards the centre.
			const double pull = 1 - double(tries) / kTries;
			pose = random_pose(board, cam, 0.5 + pull * (gx - 0.5), 0.5 + pull * (gy - 0.5), rng);
		} while (!acceptable(pose, points, cam));
		poses.push_back(pose);
	}
	return poses;
}

namespace {

constexpr double kMaxTurn = 30 * kDeg; // the board's turn in the floor's plane

// The board with its centre at floor point P, turned by yaw: board z along n (into the floor),
// x to the camera's right at yaw 0, y = z cross x towards the camera.
BoardPose on_floor(const mvod_board &board, const cv::Vec3d &n, const cv::Vec3d &P, double yaw)
{
	const cv::Vec3d f = cv::normalize(cv::Vec3d(0, 0, 1) - n[2] * n), g = n.cross(f);
	const cv::Vec3d x = std::cos(yaw) * g + std::sin(yaw) * f, y = n.cross(x);
	const cv::Matx33d R(x[0], y[0], n[0], x[1], y[1], n[1], x[2], y[2], n[2]);
	int across, down;
	mvod_board_squares(&board, &across, &down);
	const cv::Vec3d centre(across * board.square_m / 2, down * board.square_m / 2, 0);
	BoardPose pose;
	cv::Rodrigues(R, pose.rvec);
	pose.t = P - R * centre;
	return pose;
}

} // namespace

std::vector<BoardPose> floor_poses(const mvod_board &board, const Camera &cam, const Floor &floor, int views,
				   uint64_t seed)
{
	const double p = floor.pitch_deg * kDeg, r = floor.roll_deg * kDeg;
	const cv::Vec3d n(std::cos(p) * std::sin(r), std::cos(p) * std::cos(r), std::sin(p));
	const std::vector<cv::Point3d> points = outline_and_corners(board);
	cv::RNG rng(stream_seed(seed, 5001));
	// The board's centre in the lower half of the floor seen below the horizon (at the image
	// centre's column): the far half shows it too small to detect.
	const double horizon = std::max(0.0, cam.cy - cam.fy * n[2] / n[1]) / cam.height;
	const double low = std::min(0.9, horizon + 0.5 * (1 - horizon));
	std::vector<BoardPose> poses;
	for (int i = 0; i < views; i++) {
		for (int tries = 0;; tries++) {
			if (tries == kTries)
				throw Failure(kExitUsage, "no view of the whole board on the floor fits in the image: "
							  "use a smaller board, a lower camera or more pitch");
			// One draw per statement: the order of evaluation of arguments is unspecified.
			const double u = rng.uniform(0.1, 0.9) * cam.width, v = rng.uniform(low, 0.95) * cam.height;
			const double yaw = rng.uniform(-kMaxTurn, kMaxTurn);
			const cv::Vec3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
			if (n.dot(ray) <= 1e-3)
				continue; // at or above the horizon
			const BoardPose pose = on_floor(board, n, floor.height_m / n.dot(ray) * ray, yaw);
			bool inside = true;
			for (const cv::Point2d &q : project(points, cam, pose))
				inside = inside && q.x >= kEdge && q.y >= kEdge && q.x <= cam.width - 1 - kEdge &&
					 q.y <= cam.height - 1 - kEdge;
			if (inside) {
				poses.push_back(pose);
				break;
			}
		}
	}
	return poses;
}

} // namespace synth
