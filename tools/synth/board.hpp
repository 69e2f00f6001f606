// Calibration-target views for mvod-synth --board: where the board is in each view, and where
// its corners land in the image.
#pragma once

#include "render.hpp"

extern "C" {
#include "mvod/board.h"
}

#include <cstdint>
#include <vector>

namespace synth {

// Board-to-camera, as OpenCV's calibrateCamera reports it: X_cam = R(rvec) * X_board + t, with
// the board frame of include/mvod/board.h. The rotation is kept as rvec so that what is
// written is exactly what was rendered.
struct BoardPose {
	cv::Vec3d rvec, t;
	Pose camera_to_board() const;
};

// Pixel positions of the board's interior corners (mvod_board_corner order) seen from pose,
// through the exact lens model (OpenCV's projectPoints or fisheye::projectPoints).
std::vector<cv::Point2d> project_corners(const mvod_board &board, const Camera &cam, const BoardPose &pose);

// `views` poses, deterministic in seed: board centres over a 3x3 grid of image positions in
// turn (jittered; moved towards the centre as far as needed to fit), the pattern spanning 30-60% of the image width, tilted up to 50 deg about
// its x and y axes, rotated in its plane up to 45 deg, seen at most 60 deg off its normal, and
// every pattern corner (the outer ones too) at least 8 px inside the image. Throws Failure when
// the lens leaves no such view.
std::vector<BoardPose> board_poses(const mvod_board &board, const Camera &cam, int views, uint64_t seed);

// A still camera above a floor, in mvod's mount convention (include/mvod/mount.h).
struct Floor {
	double height_m = 0, pitch_deg = 0, roll_deg = 0;
};

// `views` poses of the board lying on the floor (printed face up, its top row the far one),
// deterministic in seed: the centre under a random image point in the lower half of the floor seen in the
// image, turned in the floor's plane up to 30 deg, every pattern corner at least 8 px inside
// the image. Throws Failure when the floor leaves no such view.
std::vector<BoardPose> floor_poses(const mvod_board &board, const Camera &cam, const Floor &floor, int views,
				   uint64_t seed);

} // namespace synth
