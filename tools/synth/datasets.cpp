#include "datasets.hpp"

#include "failure.hpp"

extern "C" {
#include "mvod/geom.h"
}

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

namespace fs = std::filesystem;

namespace synth {

namespace {

Pose compose(const Pose &a, const Pose &b)
{
	return {a.R * b.R, a.R * b.t + a.t};
}

Pose inverse(const Pose &p)
{
	return {p.R.t(), -(p.R.t() * p.t)};
}

void open_file(const fs::path &file, std::ofstream &out, const char *header)
{
	out.open(file);
	out << header;
	if (!out)
		throw Failure(kExitFailure, "cannot write " + file.string() + ": " + std::strerror(errno));
}

// "t tx ty tz" then the quaternion, w first (EuRoC, comma-separated) or last (TUM).
std::string pose_text(const Pose &p, bool euroc)
{
	double R[9], q[4];
	for (int i = 0; i < 9; i++)
		R[i] = p.R.val[i];
	mvod_rot_to_quat(R, q);
	char line[256];
	if (euroc)
		std::snprintf(line, sizeof line, ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0,0,0,0,0,0,0,0,0\n", p.t[0],
			      p.t[1], p.t[2], q[0], q[1], q[2], q[3]);
	else
		std::snprintf(line, sizeof line, " %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", p.t[0], p.t[1], p.t[2],
			      q[1], q[2], q[3], q[0]);
	return line;
}

std::string numbers(const double *v, int n)
{
	std::string s;
	for (int i = 0; i < n; i++) {
		char x[32];
		std::snprintf(x, sizeof x, "%s%.17g", i ? ", " : "", v[i]);
		s += x;
	}
	return s;
}

} // namespace

Pose dataset_from_world()
{
	// Columns: where mvod's x (right), y (down) and z (forward) point in a z-up world.
	return {cv::Matx33d(0, 0, 1, -1, 0, 0, 0, -1, 0), cv::Vec3d(4.688, -1.786, 0.783)};
}

Pose euroc_body_to_camera()
{
	// Columns: where the camera's x (right), y (down) and z (forward) point in a
	// forward-left-up body; then the camera tilted 2 degrees down about its x.
	const cv::Matx33d flu = dataset_from_world().R;
	cv::Matx33d tilt;
	cv::Rodrigues(cv::Vec3d(-2 * CV_PI / 180, 0, 0), tilt);
	return {flu * tilt, cv::Vec3d(-0.0216, -0.0647, 0.0098)};
}

DatasetWriter::DatasetWriter(Layout layout, const fs::path &dir, const Camera &cam, double fps) : layout_(layout)
{
	const bool euroc = layout == Layout::Euroc;
	const fs::path cam0 = dir / "mav0" / "cam0";
	images_ = euroc ? cam0 / "data" : dir / "rgb";
	index_path_ = euroc ? cam0 / "data.csv" : dir / "rgb.txt";
	gt_path_ = euroc ? dir / "mav0" / "state_groundtruth_estimate0" / "data.csv" : dir / "groundtruth.txt";
	std::error_code ec;
	fs::create_directories(images_, ec);
	if (!ec)
		fs::create_directories(gt_path_.parent_path(), ec);
	if (ec)
		throw Failure(kExitFailure, "cannot create " + images_.string() + ": " + ec.message());
	if (euroc)
		write_sensor(cam, fps);
	open_file(index_path_, index_, euroc ? "#timestamp [ns],filename\n" : "# color images\n# timestamp filename\n");
	open_file(gt_path_, gt_,
		  euroc ? "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
			  "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
			  "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
			  "b_a_RS_S_z [m s^-2]\n"
			: "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n");
}

void DatasetWriter::write_sensor(const Camera &cam, double fps) const
{
	if (!cam.fisheye && cam.dist.size() > 4)
		throw Failure(kExitUsage, "--format euroc: EuRoC's radial-tangential model has 4 coefficients "
					  "(k1 k2 p1 p2), not k3 as well");
	const Pose bs = euroc_body_to_camera();
	double T[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}, K[4] = {cam.fx, cam.fy, cam.cx, cam.cy};
	for (int r = 0; r < 3; r++) {
		for (int c = 0; c < 3; c++)
			T[4 * r + c] = bs.R(r, c);
		T[4 * r + 3] = bs.t[r];
	}
	std::vector<double> d = cam.dist;
	d.resize(4, 0.0);
	const std::string text = "# General sensor definitions.\nsensor_type: camera\ncomment: mvod-synth cam0\n\n"
				 "# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n  data: [" +
				 numbers(T, 16) + "]\n\n# Camera specific definitions.\nrate_hz: " + numbers(&fps, 1) +
				 "\nresolution: [" + std::to_string(cam.width) + ", " + std::to_string(cam.height) +
				 "]\ncamera_model: pinhole\nintrinsics: [" + numbers(K, 4) + "] #fu, fv, cu, cv\n" +
				 "distortion_model: " + (cam.fisheye ? "equidistant" : "radial-tangential") +
				 "\ndistortion_coefficients: [" + numbers(d.data(), 4) + "]\n";
	const fs::path file = index_path_.parent_path() / "sensor.yaml";
	std::ofstream out(file);
	out << text;
	if (!out)
		throw Failure(kExitFailure, "cannot write " + file.string());
}

void DatasetWriter::add(double t, const Pose &pose, const cv::Mat &image)
{
	char stamp[32];
	Pose gt = compose(dataset_from_world(), pose);
	if (layout_ == Layout::Euroc) {
		std::snprintf(stamp, sizeof stamp, "%lld", (long long)(kEurocStartNs + std::llround(t * 1e9)));
		gt = compose(gt, inverse(euroc_body_to_camera())); // the body's pose: T_RB = T_RC T_BS^-1
	} else {
		const long long us = kTumStartUs + std::llround(t * 1e6);
		std::snprintf(stamp, sizeof stamp, "%lld.%06lld", us / 1000000, us % 1000000);
	}
	const std::string name = std::string(stamp) + ".png";
	const fs::path file = images_ / name;
	if (!cv::imwrite(file.string(), image))
		throw Failure(kExitFailure, "cannot write " + file.string());
	const bool euroc = layout_ == Layout::Euroc;
	index_ << stamp << (euroc ? "," : " rgb/") << name << "\n" << std::flush;
	gt_ << stamp << pose_text(gt, euroc) << std::flush;
}

void DatasetWriter::close()
{
	index_.close();
	gt_.close();
	if (!index_ || !gt_)
		throw Failure(kExitFailure, "cannot write " + index_path_.string() + " or " + gt_path_.string());
}

} // namespace synth
