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
#include <cstdlib>
#include <cstring>
#include <string>

namespace fs = std::filesystem;

namespace synth {

namespace {

std::string number(double v)
{
	return exact_number(v, 'g', 15);
}

std::string numbers(const double *v, int n, const char *sep = ", ")
{
	std::string s;
	for (int i = 0; i < n; i++)
		s += (i ? sep : "") + number(v[i]);
	return s;
}

// "t tx ty tz" then the quaternion, w first (EuRoC, comma-separated) or last (TUM).
std::string pose_text(const Pose &p, bool euroc)
{
	double R[9], q[4];
	for (int i = 0; i < 9; i++)
		R[i] = p.R.val[i];
	mvod_rot_to_quat(R, q);
	const double v[7] = {p.t[0],
			     p.t[1],
			     p.t[2],
			     euroc ? q[0] : q[1],
			     euroc ? q[1] : q[2],
			     euroc ? q[2] : q[3],
			     euroc ? q[3] : q[0]};
	// EuRoC's rows go on with velocity and the IMU biases (9 columns), zero here.
	return (euroc ? "," : " ") + numbers(v, 7, euroc ? "," : " ") +
	       (euroc ? ",0,0,0,0,0,0,0,0,0\n" : "\n");
}

enum class Layout { Euroc, Tum, TumMono };

// EuRoC MAV (the ASL dataset format), TUM RGB-D and TUM monoVO, which share a frame index, an
// images folder and, but for monoVO, a ground-truth file.
class DatasetWriter : public LayoutWriter {
public:
	DatasetWriter(Layout layout, const fs::path &dir, const Camera &cam, double fps);
	void add(double t, const Pose &pose, const cv::Mat &image) override;
	void close() override;

private:
	void write_sensor(const Camera &cam, double fps) const;
	void write_camera_txt(const Camera &cam, const fs::path &dir) const;
	Layout layout_;
	int frames_ = 0;
	fs::path images_; // where the frames go
	fs::path index_path_, gt_path_;
	std::ofstream index_, gt_;
};

} // namespace

std::string exact_number(double v, char conv, int min_digits)
{
	char s[48];
	const char format[] = {'%', '.', '*', conv, '\0'};
	for (int digits = min_digits; digits <= 17; digits++) {
		std::snprintf(s, sizeof s, format, digits, v);
		if (std::strtod(s, nullptr) == v)
			break;
	}
	return s;
}

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
	out.open(file, std::ios::binary); // the published line ends, CRLF where they are
	out << header;
	if (!out)
		throw Failure(kExitFailure,
			      "cannot write " + file.string() + ": " + std::strerror(errno));
}

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

// The headers of the published files: MH_01_easy's cam0/data.csv (CRLF, as the EuRoC-rs
// crate's test_data copy of it has) and state_groundtruth_estimate0/data.csv (LF); TUM
// RGB-D's rgb.txt and groundtruth.txt (its "file formats" page).
static const char kEurocIndexHeader[] = "#timestamp [ns],filename\r\n";
static const char kEurocGtHeader[] =
	"#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
	"q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
	"b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
	"b_a_RS_S_z [m s^-2]\n";

DatasetWriter::DatasetWriter(Layout layout, const fs::path &dir, const Camera &cam, double fps)
    : layout_(layout)
{
	const bool euroc = layout == Layout::Euroc, mono = layout == Layout::TumMono;
	const fs::path cam0 = dir / "mav0" / "cam0";
	images_ = euroc ? cam0 / "data" : dir / (mono ? "images" : "rgb");
	index_path_ = euroc ? cam0 / "data.csv" : dir / (mono ? "times.txt" : "rgb.txt");
	gt_path_ = euroc ? dir / "mav0" / "state_groundtruth_estimate0" / "data.csv"
			 : dir / "groundtruth.txt";
	std::error_code ec;
	fs::create_directories(images_, ec);
	if (!ec)
		fs::create_directories(gt_path_.parent_path(), ec);
	if (ec)
		throw Failure(kExitFailure, "cannot create " + images_.string() + ": " + ec.message());
	if (euroc)
		write_sensor(cam, fps);
	if (mono)
		write_camera_txt(cam, dir);
	open_file(index_path_, index_,
		  euroc  ? kEurocIndexHeader
		  : mono ? ""
			 : "# color images\n# timestamp filename\n");
	if (!mono) // monoVO publishes no ground truth of every frame
		open_file(gt_path_, gt_,
			  euroc ? kEurocGtHeader
				: "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n");
}

// sensor.yaml laid out as MH_01_easy's cam0 one is published (the ASL dataset format): the
// comments, T_BS's data a row per line aligned on the sign, no newline at the end.
void DatasetWriter::write_sensor(const Camera &cam, double fps) const
{
	if (cam.fov || (!cam.fisheye && cam.dist.size() > 4))
		throw Failure(
		    kExitUsage,
		    "--format euroc: EuRoC's sensor.yaml has radial-tangential (k1 k2 p1 p2) "
		    "and equidistant lenses only");
	const Pose bs = euroc_body_to_camera();
	std::string rows;
	for (int r = 0; r < 4; r++) {
		const double row[4] = {r < 3 ? bs.R(r, 0) : 0.0, r < 3 ? bs.R(r, 1) : 0.0,
				       r < 3 ? bs.R(r, 2) : 0.0, r < 3 ? bs.t[r] : 1.0};
		rows += std::string(r ? (row[0] < 0 ? ",\n        " : ",\n         ") : "") +
			numbers(row, 4);
	}
	const double K[4] = {cam.fx, cam.fy, cam.cx, cam.cy};
	std::vector<double> d = cam.dist;
	d.resize(4, 0.0);
	const std::string text =
	    "# General sensor definitions.\nsensor_type: camera\ncomment: mvod-synth cam0\n\n"
	    "# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n  data: [" +
	    rows + "]\n\n# Camera specific definitions.\nrate_hz: " + number(fps) +
	    "\nresolution: [" + std::to_string(cam.width) + ", " + std::to_string(cam.height) +
	    "]\ncamera_model: pinhole\nintrinsics: [" + numbers(K, 4) + "] #fu, fv, cu, cv\n" +
	    "distortion_model: " + (cam.fisheye ? "equidistant" : "radial-tangential") +
	    "\ndistortion_coefficients: [" + numbers(d.data(), 4) + "]";
	const fs::path file = index_path_.parent_path() / "sensor.yaml";
	std::ofstream out(file, std::ios::binary);
	out << text;
	if (!out)
		throw Failure(kExitFailure, "cannot write " + file.string());
}

// DSO's camera.txt in the relative form TUM monoVO ships (tum-vision/mono_dataset_code reads
// it): fx / w, fy / h, (cx + 0.5) / w, (cy + 0.5) / h; the FOV lens as 5 bare numbers, the
// others by DSO's names; then the size, and DSO's crop to the same size.
void DatasetWriter::write_camera_txt(const Camera &cam, const fs::path &dir) const
{
	if (!cam.fisheye && !cam.fov && cam.dist.size() > 4)
		throw Failure(
		    kExitUsage,
		    "--format tum-mono: DSO's RadTan lens has 4 coefficients (k1 k2 p1 p2)");
	std::vector<double> v = {cam.fx / cam.width, cam.fy / cam.height, (cam.cx + 0.5) / cam.width,
				 (cam.cy + 0.5) / cam.height};
	v.insert(v.end(), cam.dist.begin(), cam.dist.end());
	const char *name = cam.fov            ? ""
			   : cam.fisheye      ? "KannalaBrandt "
			   : cam.dist.empty() ? "Pinhole "
					      : "RadTan ";
	if (cam.dist.empty())
		v.push_back(0);
	else if (!cam.fov && !cam.fisheye)
		v.resize(8, 0.0);
	const std::string size = std::to_string(cam.width) + " " + std::to_string(cam.height) + "\n";
	const std::string text =
	    name + numbers(v.data(), int(v.size()), " ") + "\n" + size + "crop\n" + size;
	std::ofstream out(dir / "camera.txt", std::ios::binary);
	out << text;
	if (!out)
		throw Failure(kExitFailure, "cannot write " + (dir / "camera.txt").string());
}

void DatasetWriter::add(double t, const Pose &pose, const cv::Mat &image)
{
	char stamp[32], name[40];
	Pose gt = compose(dataset_from_world(), pose);
	if (layout_ == Layout::Euroc) {
		std::snprintf(stamp, sizeof stamp, "%lld",
			      (long long)(kEurocStartNs + std::llround(t * 1e9)));
		gt = compose(
		    gt, inverse(euroc_body_to_camera())); // the body's pose: T_RB = T_RC T_BS^-1
	} else {
		const long long us = kTumStartUs + std::llround(t * 1e6);
		std::snprintf(stamp, sizeof stamp, "%lld.%06lld", us / 1000000, us % 1000000);
	}
	if (layout_ == Layout::TumMono)
		std::snprintf(name, sizeof name, "%05d.png", frames_);
	else
		std::snprintf(name, sizeof name, "%s.png", stamp);
	const fs::path file = images_ / name;
	if (!cv::imwrite(file.string(), image))
		throw Failure(kExitFailure, "cannot write " + file.string());
	if (layout_ == Layout::Euroc)
		index_ << stamp << "," << name << "\r\n";
	else if (layout_ == Layout::Tum)
		index_ << stamp << " rgb/" << name << "\n";
	else // monoVO: "id time exposure", the exposure in milliseconds
		index_ << std::string(name, 5) << " " << stamp << " 10.0\n";
	index_ << std::flush;
	if (layout_ != Layout::TumMono)
		gt_ << stamp << pose_text(gt, layout_ == Layout::Euroc) << std::flush;
	frames_++;
}

void DatasetWriter::close()
{
	index_.close();
	if (gt_.is_open())
		gt_.close();
	if (!index_ || !gt_)
		throw Failure(kExitFailure,
			      "cannot write " + index_path_.string() + " or " + gt_path_.string());
}

std::unique_ptr<LayoutWriter> make_layout_writer(const std::string &format, const fs::path &dir,
						 const Camera &cam, double fps)
{
	if (format == "kitti-raw")
		return make_kitti_raw_writer(dir, cam);
	const Layout layout = format == "euroc" ? Layout::Euroc
			      : format == "tum" ? Layout::Tum
						: Layout::TumMono;
	return std::make_unique<DatasetWriter>(layout, dir, cam, fps);
}

} // namespace synth
