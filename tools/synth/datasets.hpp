// The public dataset layouts mvod reads as sources (euroc:, tum:), written frame by frame, so
// that tests can read one rendering back through each layout and through images: and compare.
#pragma once

#include "render.hpp"
#include "world.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>

namespace synth {

enum class Layout { Euroc, Tum };

// EuRoC's clock: nanoseconds from MH_01_easy's first camera frame, whose sub-microsecond digits
// (584 ns) make a rounding or a trip through double visible.
constexpr int64_t kEurocStartNs = 1403636579763555584;
// TUM's clock: microseconds from freiburg1_xyz's first colour frame (its files have 6 decimals).
constexpr int64_t kTumStartUs = 1305031102175304;

// T_BS, the camera in the body frame as EuRoC's sensor.yaml gives it: the camera's axes turned
// into a forward-left-up body, tilted 2 degrees down, with a 7 cm lever arm (EuRoC's cam0 has
// one like it); so a body pose taken for the camera's is metres off.
Pose euroc_body_to_camera();
// The dataset's world (EuRoC's and TUM's motion-capture frame) from mvod's: z up, x along the
// first camera's view, moved away from the origin.
Pose dataset_from_world();

class DatasetWriter {
public:
	// Creates the layout's folders and index files in dir; cam is what sensor.yaml says.
	DatasetWriter(Layout layout, const std::filesystem::path &dir, const Camera &cam, double fps);
	// One frame at t seconds (from 0), its camera-to-world pose in mvod's world.
	void add(double t, const Pose &pose, const cv::Mat &image);
	void close();

private:
	void write_sensor(const Camera &cam, double fps) const;
	Layout layout_;
	std::filesystem::path images_; // where the frames go
	std::filesystem::path index_path_, gt_path_;
	std::ofstream index_, gt_;
};

} // namespace synth
