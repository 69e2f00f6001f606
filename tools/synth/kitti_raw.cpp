// The KITTI raw layout, as the raw data devkit's readme describes it and pykitti's raw.py reads
// it: DATE/DATE_drive_NNNN_sync/image_00/{data/NNNNNNNNNN.png,timestamps.txt} (calendar times,
// nine decimals), oxts/{data/NNNNNNNNNN.txt,timestamps.txt} (one OXTS packet a frame, 30
// values: lat lon alt roll pitch yaw, then velocities, accelerations, rates, accuracies and
// five counts), and beside the drive the date's calib_cam_to_cam.txt, calib_imu_to_velo.txt,
// calib_velo_to_cam.txt.
#include "datasets.hpp"

#include "failure.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace synth {

namespace {

constexpr char kDate[] = "2011_09_26";
constexpr char kDrive[] = "2011_09_26_drive_0001_sync";
// The first frame's time: drive 0001's first image_00 line, 2011-09-26 13:02:25.964389445.
constexpr int kStartSec = 25;
constexpr long long kStartNs = 964389445;
// Where the drive starts: near Karlsruhe, where KITTI drove (degrees, metres).
constexpr double kLat0 = 49.011213, kLon0 = 8.4235924, kAlt0 = 112.83;
constexpr double kEarthRadius = 6378137; // the devkit's (and pykitti's) Mercator sphere, metres

// 2011_09_26's files as the KITTI raw download has them: calib_imu_to_velo.txt and
// calib_velo_to_cam.txt whole; of calib_cam_to_cam.txt camera 00's lines, S_rect_00 and
// P_rect_00 then replaced by the rendering's size and intrinsics.
constexpr char kImuToVelo[] =
    "calib_time: 25-May-2012 16:47:16\n"
    "R: 9.999976e-01 7.553071e-04 -2.035826e-03 -7.854027e-04 9.998898e-01 -1.482298e-02 "
    "2.024406e-03 1.482454e-02 9.998881e-01\n"
    "T: -8.086759e-01 3.195559e-01 -7.997231e-01\n";
constexpr char kVeloToCam[] =
    "calib_time: 15-Mar-2012 11:37:16\n"
    "R: 7.533745e-03 -9.999714e-01 -6.166020e-04 1.480249e-02 7.280733e-04 -9.998902e-01 "
    "9.998621e-01 7.523790e-03 1.480755e-02\n"
    "T: -4.069766e-03 -7.631618e-02 -2.717806e-01\n"
    "delta_f: 0.000000e+00 0.000000e+00\n"
    "delta_c: 0.000000e+00 0.000000e+00\n";
constexpr char kCamToCamHead[] =
    "calib_time: 09-Jan-2012 13:57:47\n"
    "corner_dist: 9.950000e-02\n"
    "S_00: 1.392000e+03 5.120000e+02\n"
    "K_00: 9.842439e+02 0.000000e+00 6.900000e+02 0.000000e+00 9.808141e+02 2.331966e+02 "
    "0.000000e+00 0.000000e+00 1.000000e+00\n"
    "D_00: -3.728755e-01 2.037299e-01 2.219027e-03 1.383707e-03 -7.233722e-02\n"
    "R_00: 1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00 "
    "0.000000e+00 0.000000e+00 1.000000e+00\n"
    "T_00: 2.573699e-16 -1.059758e-16 1.614870e-16\n";
constexpr double kRectR[9] = {9.999239e-01, 9.837760e-03,  -7.445048e-03, -9.869795e-03, 9.999421e-01,
			      -4.278459e-03, 7.402527e-03, 4.351614e-03,  9.999631e-01};

// The numbers after "KEY:" in text (the R and T lines above).
std::vector<double> values(const char *text, const char *key)
{
	std::istringstream in(std::strstr(text, key) + std::strlen(key));
	std::string line;
	std::getline(in, line);
	std::istringstream nums(line);
	std::vector<double> v;
	for (double x; nums >> x;)
		v.push_back(x);
	return v;
}

Pose rigid(const char *text)
{
	const std::vector<double> R = values(text, "\nR: "), t = values(text, "\nT: ");
	return {cv::Matx33d(R.data()), cv::Vec3d(t[0], t[1], t[2])};
}

// The nearest rotation: the files' 7 significant digits leave their rotations 1e-7 from one.
cv::Matx33d orthonormal(const cv::Matx33d &M)
{
	cv::Matx33d U, Vt;
	cv::Vec3d w;
	cv::SVD::compute(M, w, U, Vt);
	return U * Vt;
}

// T_cam0_imu: rectified camera 0 from the IMU, R_rect_00 (velo_to_cam) (imu_to_velo), as
// pykitti's raw.py composes it (camera 0's P_rect_00 shifts nothing).
Pose camera_from_imu()
{
	const Pose p = compose(compose({cv::Matx33d(kRectR), cv::Vec3d()}, rigid(kVeloToCam)),
			       rigid(kImuToVelo));
	return {orthonormal(p.R), p.t};
}

// "%e" as the files print numbers ("7.215377e+02"), with the digits reading v back takes.
std::string sci(double v)
{
	return exact_number(v, 'e', 6);
}

void write_text(const fs::path &file, const std::string &text)
{
	std::ofstream out(file, std::ios::binary);
	out << text;
	if (!out)
		throw Failure(kExitFailure,
			      "cannot write " + file.string() + ": " + std::strerror(errno));
}

void write_calibration(const fs::path &date, const Camera &cam)
{
	write_text(date / "calib_imu_to_velo.txt", kImuToVelo);
	write_text(date / "calib_velo_to_cam.txt", kVeloToCam);
	std::string rect = "R_rect_00:";
	for (double v : kRectR)
		rect += " " + sci(v);
	const double P[12] = {cam.fx, 0, cam.cx, 0, 0, cam.fy, cam.cy, 0, 0, 0, 1, 0};
	std::string p = "P_rect_00:";
	for (double v : P)
		p += " " + sci(v);
	write_text(date / "calib_cam_to_cam.txt",
		   std::string(kCamToCamHead) + "S_rect_00: " + sci(cam.width) + " " +
		       sci(cam.height) + "\n" + rect + "\n" + p + "\n");
}

// The devkit's Mercator projection (pykitti's pose_from_oxts_packet), east and north metres
// at the scale of the first packet's latitude, and back.
cv::Vec2d mercator(double lat, double lon, double scale)
{
	return {scale * lon * M_PI * kEarthRadius / 180,
		scale * kEarthRadius * std::log(std::tan((90 + lat) * M_PI / 360))};
}

cv::Vec2d geographic(const cv::Vec2d &m, double scale)
{
	return {360 / M_PI * std::atan(std::exp(m[1] / (scale * kEarthRadius))) - 90,
		m[0] * 180 / (scale * M_PI * kEarthRadius)};
}

class KittiRawWriter : public LayoutWriter {
public:
	KittiRawWriter(const fs::path &dir, const Camera &cam);
	void add(double t, const Pose &pose, const cv::Mat &image) override;
	void close() override;

private:
	std::string oxts(const Pose &camera) const;
	fs::path drive_;
	std::ofstream image_times_, oxts_times_;
	int frames_ = 0;
	Pose cam_imu_;     // T_cam0_imu of the calibration written
	Pose enu_world_;   // the OXTS world (x east, y north, z up) from mvod's
	cv::Vec3d origin_; // the first IMU position, east-north-up metres
	double scale_;     // cos(latitude) of the first packet
};

KittiRawWriter::KittiRawWriter(const fs::path &dir, const Camera &cam)
    : drive_(dir / kDate / kDrive), cam_imu_(camera_from_imu()),
      scale_(std::cos(kLat0 * M_PI / 180))
{
	if (!cam.dist.empty())
		throw Failure(
		    kExitUsage,
		    "--format kitti-raw: the _sync drives' images are rectified, so no lens");
	// mvod's first camera looks east, level: its x (right) south, y (down) down, z east.
	enu_world_ = {cv::Matx33d(0, 0, 1, -1, 0, 0, 0, -1, 0), cv::Vec3d(0, 0, 0)};
	std::error_code ec;
	for (const char *sub : {"image_00/data", "oxts/data"})
		fs::create_directories(drive_ / sub, ec);
	if (ec)
		throw Failure(kExitFailure, "cannot create " + drive_.string() + ": " + ec.message());
	write_calibration(dir / kDate, cam);
	open_file(drive_ / "image_00" / "timestamps.txt", image_times_, "");
	open_file(drive_ / "oxts" / "timestamps.txt", oxts_times_, "");
}

// The packet of the IMU under camera (camera-to-world, mvod's world), 30 values.
std::string KittiRawWriter::oxts(const Pose &camera) const
{
	const Pose imu = compose(compose(enu_world_, camera), cam_imu_);
	const cv::Vec2d geo =
	    geographic(mercator(kLat0, kLon0, scale_) + cv::Vec2d(imu.t[0], imu.t[1]) -
			   cv::Vec2d(origin_[0], origin_[1]),
		       scale_);
	const cv::Matx33d &R = imu.R; // Rz(yaw) Ry(pitch) Rx(roll), the devkit's order
	const double v[6] = {geo[0],
			     geo[1],
			     kAlt0 + imu.t[2] - origin_[2],
			     std::atan2(R(2, 1), R(2, 2)),
			     std::atan2(-R(2, 0), std::hypot(R(2, 1), R(2, 2))),
			     std::atan2(R(1, 0), R(0, 0))};
	std::string line;
	for (double x : v) {
		char s[32];
		std::snprintf(s, sizeof s, "%.17g ", x);
		line += s;
	}
	// Velocities, accelerations and rates (17 values) zero; accuracies, navstat, satellites
	// and the three modes as a drive's packets have them.
	return line + "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0.05 0.02 4 11 6 6 6\n";
}

void KittiRawWriter::add(double t, const Pose &pose, const cv::Mat &image)
{
	if (frames_ == 0) // the drive starts at (kLat0, kLon0, kAlt0)
		origin_ = compose(compose(enu_world_, pose), cam_imu_).t;
	char name[32];
	std::snprintf(name, sizeof name, "%010d", frames_);
	const fs::path png = drive_ / "image_00" / "data" / (std::string(name) + ".png");
	if (!cv::imwrite(png.string(), image))
		throw Failure(kExitFailure, "cannot write " + png.string());
	write_text(drive_ / "oxts" / "data" / (std::string(name) + ".txt"), oxts(pose));
	// Calendar time of frame t, nine decimals: 2011-09-26 13:02:25.964389445 onwards.
	const long long ns = kStartNs + std::llround(t * 1e9);
	std::tm start = {};
	start.tm_year = 2011 - 1900;
	start.tm_mon = 8;
	start.tm_mday = 26;
	start.tm_hour = 13;
	start.tm_min = 2;
	start.tm_sec = kStartSec;
	const std::time_t sec = timegm(&start) + std::time_t(ns / 1000000000);
	std::tm when;
	char stamp[64];
	const size_t n = std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S", gmtime_r(&sec, &when));
	std::snprintf(stamp + n, sizeof stamp - n, ".%09lld\n", ns % 1000000000);
	image_times_ << stamp << std::flush;
	oxts_times_ << stamp << std::flush;
	frames_++;
}

void KittiRawWriter::close()
{
	image_times_.close();
	oxts_times_.close();
	if (!image_times_ || !oxts_times_)
		throw Failure(kExitFailure,
			      "cannot write " + (drive_ / "image_00" / "timestamps.txt").string());
}

} // namespace

std::unique_ptr<LayoutWriter> make_kitti_raw_writer(const fs::path &dir, const Camera &cam)
{
	return std::make_unique<KittiRawWriter>(dir, cam);
}

} // namespace synth
