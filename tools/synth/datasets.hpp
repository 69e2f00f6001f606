// The public dataset layouts mvod reads as sources (euroc:, tum:, kitti-raw:), written frame by
// frame with the published files' quirks, so that tests read one rendering back through each
// layout's parser as it meets real data, and through images: to compare.
#pragma once

#include "render.hpp"
#include "world.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace synth {

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
Pose compose(const Pose &a, const Pose &b);
Pose inverse(const Pose &p);

// One layout's files, written frame by frame.
class LayoutWriter {
public:
	virtual ~LayoutWriter() = default;
	// One frame at t seconds (from 0), its camera-to-world pose in mvod's world.
	virtual void add(double t, const Pose &pose, const cv::Mat &image) = 0;
	virtual void close() = 0;
};

// --format euroc, tum, tum-mono or kitti-raw into dir; cam is what the layout's calibration
// file says, fps the frame rate. Refuses (kExitUsage) a lens the layout cannot describe.
std::unique_ptr<LayoutWriter> make_layout_writer(const std::string &format,
						 const std::filesystem::path &dir,
						 const Camera &cam, double fps);

// The KITTI raw layout (kitti_raw.cpp).
std::unique_ptr<LayoutWriter> make_kitti_raw_writer(const std::filesystem::path &dir,
						    const Camera &cam);

// v printed with conv ('g' or 'e') and the fewest digits from min_digits that read back as v:
// the files say exactly what was rendered, in the form the published ones print.
std::string exact_number(double v, char conv, int min_digits);

// Opens file for writing with header first; throws on failure.
void open_file(const std::filesystem::path &file, std::ofstream &out, const char *header);

} // namespace synth
