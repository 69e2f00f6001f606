// Camera trajectories: the built-in paths and KITTI/TUM pose files.
#pragma once

#include "world.hpp"

#include <string>
#include <vector>

namespace synth {

struct Trajectory {
	std::vector<double> times; // seconds
	std::vector<Pose> poses;   // camera-to-world, one per frame
	// What the street is built along: the camera positions, or for a loop one whole lap of it
	// however many frames are rendered, so that the loop is enclosed from the first frame.
	std::vector<cv::Vec3d> skeleton;
	bool closed = false;
};

// The built-in path names, comma separated, for help and error messages.
std::string builtin_path_names();
bool is_builtin_path(const std::string &name);

// `frames` poses at `fps` along a built-in path, moving at `speed` m/s. All start at the
// identity, heading along +z; turns are to the left (towards -x).
Trajectory builtin_path(const std::string &name, int frames, double fps, double speed);

// The first `frames` poses of a KITTI (12 columns) or TUM (8 columns) file, or all of them when
// frames is 0. TUM timestamps are kept; KITTI poses are spaced 1/fps. Throws Failure.
Trajectory load_path(const std::string &file, int frames, double fps);

} // namespace synth
