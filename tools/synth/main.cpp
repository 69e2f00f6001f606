// mvod-synth: renders a textured 3-D street seen by a moving camera, with exact ground truth,
// so that mvod's visual odometry and calibration can be tested against known answers.

#include "board.hpp"
#include "datasets.hpp"
#include "failure.hpp"
#include "paths.hpp"
#include "render.hpp"
#include "video.hpp"
#include "world.hpp"

extern "C" {
#include "mvod/board.h"
#include "mvod/calib.h"
#include "mvod/traj.h"
#include "util/atomic_file.h"
}

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <getopt.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace synth;

namespace {

const char kUsage[] = R"(Usage: mvod-synth --out DIR [options]
       mvod-synth --out DIR --board SPEC [--views N] [camera and image options]

Renders a textured 3-D street (ground, facades, boxes, poles, sky) seen by a moving camera,
with the exact camera poses and intrinsics, for testing visual odometry and calibration.
The same arguments and seed always give identical frames.

Writes into DIR (created if missing; earlier outputs there are replaced):
  video.mkv                lossless 8-bit grey video (--format mkv): FFV1, or uncompressed
                           with --codec raw
  images/000000.png ...    8-bit grey PNG per frame, and images/times.txt (--format png)
  mav0/cam0/data.csv, data/NS.png, sensor.yaml, mav0/state_groundtruth_estimate0/data.csv
                           the EuRoC MAV layout (--format euroc): nanosecond times from
                           1403636579763555584; sensor.yaml with the intrinsics and a T_BS
                           taking the camera's axes to a forward-left-up body (tilted 2 deg, a
                           7 cm lever arm); the ground truth as body poses (camera pose times
                           T_BS^-1) in a z-up world
  rgb.txt, rgb/T.png, groundtruth.txt
                           the TUM RGB-D layout (--format tum): times from 1305031102.175304 s;
                           the ground truth as camera poses in the same z-up world
  times.txt, images/NNNNN.png, camera.txt
                           the TUM monoVO layout (--format tum-mono): "id time exposure" lines
                           from the TUM clock; DSO's camera.txt in the relative form (the lens
                           as 5 bare numbers for --fov, as monoVO ships it); no ground truth
                           beyond gt.tum and gt.kitti
  2011_09_26/calib_*.txt, 2011_09_26/2011_09_26_drive_0001_sync/
                           the KITTI raw layout (--format kitti-raw, no lens): image_00/data/
                           NNNNNNNNNN.png and timestamps.txt (calendar times from 2011-09-26
                           13:02:25.964389445), oxts/data/NNNNNNNNNN.txt (the IMU's pose as GPS
                           latitude, longitude, altitude, roll, pitch, yaw), calib_cam_to_cam.txt
                           (P_rect_00 the intrinsics), calib_imu_to_velo.txt and
                           calib_velo_to_cam.txt (KITTI's 2011_09_26 extrinsics)
  times.txt                timestamp of every frame in seconds, one per line (but for
                           --format tum-mono, whose times.txt is monoVO's)
  gt.tum, gt.kitti         camera-to-world pose of every frame (OpenCV axes: x right, y down,
                           z forward; metres; for built-in paths the first camera is the world)
  calib.json               intrinsics and distortion (mvod-calibration/1)

With --board SPEC, views of a calibration target instead of a street (see below), and also:
  board_poses.txt          "VIEW RX RY RZ TX TY TZ" per view: board-to-camera rotation vector
                           and translation (metres), X_cam = R(r) X_board + t, as OpenCV's
                           calibrateCamera reports them; board frame of include/mvod/board.h
                           (origin at the pattern's top-left outer corner, x right, y down)
  corners.txt              "VIEW ID U V" per interior corner: the exact pixel position (OpenCV
                           convention: pixel centres at integers) of corner ID (row-major, as
                           OpenCV's chessboard and ChArUco detectors number them), projected
                           through the exact lens; every corner of every view is in the image
  gt.tum, gt.kitti         the camera-to-board poses, one per view

Options:
  --out DIR              output directory (required)
  --path NAME|FILE       camera path (default forward); the ground is 1.6 m below the camera:
      forward            straight along +z with a slight sway (+-3 cm sideways, +-0.5 deg yaw,
                         +-0.3 deg pitch)
      turn               straight, a smooth 90 deg left turn over the middle 40% of the
                         distance, then straight
      circle             a left circle of radius 6 m, inside a ring of facades
      figure8            a lap of a left circle then one of a right circle (radius 6 m),
                         touching at the start
      rotate-in-place    yaw swinging +-30 deg (left first, period 6 s) about the camera
                         centre, no translation
      static             the identity pose in every frame
      stop-go            a gentle left curve (radius 40 m) at a changing speed: 0.5 to 1.5
                         times --speed over the first quarter of the time, braking to a stop
                         at 40%, standing until 50%, pulling away to --speed by 65%
      FILE               KITTI (12 numbers per line) or TUM (t tx ty tz qx qy qz qw) poses,
                         camera-to-world, metres, y down; a street is built along them
  --frames N             frames to render (default 60; for a FILE its first N poses,
                         default all)
  --fps F                frame rate in Hz (default 10): frame i is at i/F s, except that TUM
                         files keep their own timestamps
  --speed V              speed along built-in paths in m/s (default 1.0)
  --size WxH             image size in pixels, 16..16384 a side, odd or even (default
                         640x480); video.mkv has exactly this size too
  --fx F, --fy F         focal lengths in pixels (default fx = 0.9 * width, fy = fx)
  --cx F, --cy F         principal point in pixels (default (width-1)/2, (height-1)/2)
  --distortion K1,K2,P1,P2[,K3]
                         radial-tangential lens distortion, OpenCV's model (default none)
  --fisheye K1,K2,K3,K4  Kannala-Brandt lens distortion, OpenCV's fisheye model
  --fov W                the FOV (arctangent) lens of DSO and PTAM, W its field of view in
                         radians, in (0, pi) (TUM monoVO's are 0.9 to 0.95); not with --board
  --noise SIGMA          additive Gaussian noise, standard deviation in grey levels (default 0)
  --blur SIGMA           Gaussian blur, standard deviation in pixels, applied before the noise
                         (default 0)
  --seed N               seed for the world, its textures and the noise (default 1)
  --format mkv|png|euroc|tum|tum-mono|kitti-raw
                         output format (default mkv); euroc's sensor.yaml holds a
                         radial-tangential lens of 4 coefficients, or --fisheye; tum-mono's
                         camera.txt any lens but a 5-coefficient one; kitti-raw's frames are
                         rectified: no lens
  --codec ffv1|raw       video.mkv's codec (default ffv1), both lossless: raw frames are 1.7
                         times FFV1's bytes on this street's textures and cost nothing to
                         decode, where FFV1 costs about as much as mvod's tracking (46e6
                         instructions a 640x480 frame)

Calibration target (--board):
  --board SPEC           charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT (COLSxROWS squares) or
                         chessboard:COLSxROWS:SQUARE_M (inner corners), e.g.
                         charuco:5x7:0.04:0.02:DICT_6X6_250 or chessboard:9x6:0.025. The
                         pattern (up to 128 texels per square, a one-square white quiet zone,
                         printed black 20 and white 224) is a plane in front of a dim textured
                         wall, ray-cast through the exact lens like the street
  --views N              views to render (default 60): board centres over a 3x3 grid of image
                         positions in turn, the pattern 30-60% of the image wide, tilted up to
                         50 deg about both board axes and rotated in its plane up to 45 deg;
                         always the whole pattern in view, at least 8 px from the border
  --inverted             invert the printed board (white markers and squares on black)
  --floor H,PITCH,ROLL   the board lies on a floor instead, seen by a still camera whose
                         centre is H metres above it, pitched PITCH deg (positive: looking
                         down) and rolled ROLL deg (positive: the floor's downward normal
                         leans to +x), mvod's mount convention: the floor's normal in the
                         camera frame is (cos P sin R, cos P cos R, sin P). Each view moves
                         the board on the floor (its centre under a random image point in
                         the nearer half of the floor in view, turned up to 30 deg), whole;
                         the dim wall behind is then 1 board-width under the floor
  Example: mvod-synth --out views/ --board chessboard:9x6:0.025 --views 40 --format png \
             --distortion -0.3,0.1,0,0,0 --noise 2
  -h, --help             show this help

Exit status: 0 on success, 1 on a run-time failure (unreadable pose file, unwritable output),
2 on bad usage.
)";

struct Options {
	std::string out;
	std::string path = "forward";
	int frames = 0; // 0: the path's default
	double fps = 10;
	int width = 640, height = 480;
	double fx = NAN, fy = NAN, cx = NAN, cy = NAN; // NAN: derived from the size
	bool fisheye = false;
	bool fov = false;
	std::vector<double> dist;
	double noise = 0, blur = 0;
	uint64_t seed = 1;
	bool png = false;
	std::string format = "mkv";
	bool raw = false; // --codec raw: video.mkv uncompressed (rawvideo, Y800) instead of FFV1
	bool codec_given = false;
	double speed = 1.0;
	std::string board; // empty: the street
	int views = 60;
	bool inverted = false;
	bool on_floor = false;
	Floor floor;
	bool street_options = false; // --path, --frames or --speed given
};

[[noreturn]] void usage_error(const std::string &message)
{
	throw Failure(kExitUsage, message + " (see --help)");
}

double parse_number(const char *option, const char *text)
{
	char *end = nullptr;
	errno = 0;
	const double v = std::strtod(text, &end);
	if (end == text || *end != '\0' || errno != 0 || !std::isfinite(v))
		usage_error(std::string("--") + option + ": '" + text + "' is not a number");
	return v;
}

double parse_positive(const char *option, const char *text)
{
	const double v = parse_number(option, text);
	if (v <= 0)
		usage_error(std::string("--") + option + " must be positive, not " + text);
	return v;
}

double parse_non_negative(const char *option, const char *text)
{
	const double v = parse_number(option, text);
	if (v < 0)
		usage_error(std::string("--") + option + " must not be negative, not " + text);
	return v;
}

uint64_t parse_unsigned(const char *option, const char *text)
{
	char *end = nullptr;
	errno = 0;
	const unsigned long long v = std::strtoull(text, &end, 10);
	if (end == text || *end != '\0' || errno != 0 || std::strchr(text, '-'))
		usage_error(std::string("--") + option + ": '" + text + "' is not a whole number >= 0");
	return v;
}

int parse_count(const char *option, const char *text)
{
	const uint64_t v = parse_unsigned(option, text);
	if (v < 1 || v > 10000000)
		usage_error(std::string("--") + option + " must be between 1 and 10000000, not " + text);
	return int(v);
}

std::vector<double> parse_list(const char *option, const char *text, size_t min, size_t max)
{
	const std::string list = text;
	std::vector<double> values;
	for (size_t start = 0;;) {
		const size_t comma = list.find(',', start);
		values.push_back(parse_number(option, list.substr(start, comma - start).c_str()));
		if (comma == std::string::npos)
			break;
		start = comma + 1;
	}
	if (values.size() < min || values.size() > max)
		usage_error(std::string("--") + option + " takes " + std::to_string(min) +
			    (max > min ? " or " + std::to_string(max) : std::string()) + " comma-separated numbers, not '" +
			    text + "'");
	return values;
}

void parse_size(const char *text, Options &o)
{
	const std::string size = text;
	const size_t x = size.find('x');
	const auto side = [&](const std::string &digits) {
		return digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 5
			       ? 0
			       : std::stoi(digits);
	};
	const int w = x == std::string::npos ? 0 : side(size.substr(0, x));
	const int h = x == std::string::npos ? 0 : side(size.substr(x + 1));
	if (w < 16 || h < 16 || w > 16384 || h > 16384)
		usage_error("--size: '" + size + "' is not WIDTHxHEIGHT with each side 16..16384 pixels");
	o.width = w;
	o.height = h;
}

Options parse_options(int argc, char **argv)
{
	enum { OUT = 256, PATH, FRAMES, FPS, SIZE, FX, FY, CX, CY, DISTORTION, FISHEYE, NOISE, BLUR, SEED, FORMAT, SPEED,
	       BOARD, CODEC, VIEWS, INVERTED, FLOOR, FOV };
	static const option longopts[] = {
		{"out", required_argument, nullptr, OUT},
		{"path", required_argument, nullptr, PATH},
		{"frames", required_argument, nullptr, FRAMES},
		{"fps", required_argument, nullptr, FPS},
		{"size", required_argument, nullptr, SIZE},
		{"fx", required_argument, nullptr, FX},
		{"fy", required_argument, nullptr, FY},
		{"cx", required_argument, nullptr, CX},
		{"cy", required_argument, nullptr, CY},
		{"distortion", required_argument, nullptr, DISTORTION},
		{"fisheye", required_argument, nullptr, FISHEYE},
		{"noise", required_argument, nullptr, NOISE},
		{"blur", required_argument, nullptr, BLUR},
		{"seed", required_argument, nullptr, SEED},
		{"format", required_argument, nullptr, FORMAT},
		{"speed", required_argument, nullptr, SPEED},
		{"board", required_argument, nullptr, BOARD},
		{"codec", required_argument, nullptr, CODEC},
		{"views", required_argument, nullptr, VIEWS},
		{"inverted", no_argument, nullptr, INVERTED},
		{"floor", required_argument, nullptr, FLOOR},
		{"fov", required_argument, nullptr, FOV},
		{"help", no_argument, nullptr, 'h'},
		{nullptr, 0, nullptr, 0},
	};

	Options o;
	bool radtan = false;
	opterr = 0; // our own messages, in our own format
	for (int c; (c = getopt_long(argc, argv, ":h", longopts, nullptr)) != -1;) {
		const char *name = c >= OUT ? longopts[c - OUT].name : "";
		switch (c) {
		case OUT: o.out = optarg; break;
		case PATH:
			o.path = optarg;
			o.street_options = true;
			break;
		case FRAMES:
			o.frames = parse_count(name, optarg);
			o.street_options = true;
			break;
		case FPS: o.fps = parse_positive(name, optarg); break;
		case SIZE: parse_size(optarg, o); break;
		case FX: o.fx = parse_positive(name, optarg); break;
		case FY: o.fy = parse_positive(name, optarg); break;
		case CX: o.cx = parse_number(name, optarg); break;
		case CY: o.cy = parse_number(name, optarg); break;
		case DISTORTION:
			o.dist = parse_list(name, optarg, 4, 5);
			radtan = true;
			break;
		case FISHEYE:
			o.dist = parse_list(name, optarg, 4, 4);
			o.fisheye = true;
			break;
		case FOV:
			o.dist = {parse_positive(name, optarg)};
			if (o.dist[0] >= M_PI)
				usage_error("--fov: W is the lens's field of view in radians, below pi");
			o.fov = true;
			break;
		case NOISE: o.noise = parse_non_negative(name, optarg); break;
		case BLUR: o.blur = parse_non_negative(name, optarg); break;
		case SEED: o.seed = parse_unsigned(name, optarg); break;
		case FORMAT:
			o.format = optarg;
			if (o.format != "mkv" && o.format != "png" && o.format != "euroc" && o.format != "tum" &&
			    o.format != "tum-mono" && o.format != "kitti-raw")
				usage_error(std::string("--format: '") + optarg +
					    "' is none of mkv, png, euroc, tum, tum-mono, kitti-raw");
			o.png = o.format == "png";
			break;
		case SPEED:
			o.speed = parse_positive(name, optarg);
			o.street_options = true;
			break;
		case BOARD: o.board = optarg; break;
		case CODEC:
			if (std::strcmp(optarg, "ffv1") != 0 && std::strcmp(optarg, "raw") != 0)
				usage_error(std::string("--codec: '") + optarg + "' is none of ffv1, raw");
			o.raw = std::strcmp(optarg, "raw") == 0;
			o.codec_given = true;
			break;
		case VIEWS: o.views = parse_count(name, optarg); break;
		case INVERTED: o.inverted = true; break;
		case FLOOR: {
			const std::vector<double> f = parse_list(name, optarg, 3, 3);
			// Beyond mvod's +-60 deg too: a board that stands rather than lies, for mvod mount's refusal.
			if (!(f[0] > 0) || std::fabs(f[1]) >= 90 || std::fabs(f[2]) >= 90)
				usage_error("--floor: HEIGHT must be positive and PITCH, ROLL within +-90 deg");
			o.floor = Floor{f[0], f[1], f[2]};
			o.on_floor = true;
			break;
		}
		case 'h':
			std::fputs(kUsage, stdout);
			std::exit(0);
		case ':': usage_error(std::string(argv[optind - 1]) + " needs a value");
		default: usage_error(std::string("unknown option '") + argv[optind - 1] + "'");
		}
	}
	if (optind < argc)
		usage_error(std::string("unexpected argument '") + argv[optind] + "'");
	if (o.out.empty())
		usage_error("--out DIR is required");
	if (o.codec_given && o.format != "mkv")
		usage_error("--codec chooses video.mkv's codec: it needs --format mkv, not " + o.format);
	if (int(radtan) + int(o.fisheye) + int(o.fov) > 1)
		usage_error("--distortion, --fisheye and --fov are three lens models: give one");
	if (o.fov && !o.board.empty())
		usage_error("--fov renders the street: the board's corners are projected through OpenCV's lens models");
	if (o.on_floor && o.board.empty())
		usage_error("--floor places a --board on the floor: give --board SPEC");
	if (!o.board.empty() && o.street_options)
		usage_error("--path, --frames and --speed describe the street; --board renders --views N views of a board");
	return o;
}

Camera camera_from(const Options &o)
{
	Camera cam;
	cam.width = o.width;
	cam.height = o.height;
	cam.fx = std::isnan(o.fx) ? 0.9 * o.width : o.fx;
	cam.fy = std::isnan(o.fy) ? cam.fx : o.fy;
	cam.cx = std::isnan(o.cx) ? (o.width - 1) / 2.0 : o.cx;
	cam.cy = std::isnan(o.cy) ? (o.height - 1) / 2.0 : o.cy;
	cam.fisheye = o.fisheye;
	cam.fov = o.fov;
	cam.dist = o.dist;
	return cam;
}

std::string quote(const std::string &arg)
{
	return arg.find_first_of(" \t\"'") == std::string::npos ? arg : "'" + arg + "'";
}

std::string errno_text(int negative_errno)
{
	return std::strerror(-negative_errno);
}

// Everything written into the output directory. Trajectory lines are added frame by frame by
// writers that leave only whole lines behind, so an interrupted run still has a valid prefix.
class Output {
public:
	Output(const Options &o, const Camera &cam, const std::string &command_line)
		: dir_(o.out), png_(o.png), raw_(o.raw), board_(o.board)
	{
		std::error_code ec;
		fs::create_directories(png_ ? dir_ / "images" : dir_, ec);
		if (ec || !fs::is_directory(dir_))
			throw Failure(kExitFailure, "cannot create output directory " + o.out + ": " +
							    (ec ? ec.message() : "not a directory"));
		if (png_)
			remove_old_frames();
		if (o.format != "mkv" && o.format != "png")
			dataset_ = make_layout_writer(o.format, dir_, cam, o.fps);
		save_calibration(cam, command_line);
		open_trajectory("gt.tum", MVOD_TRAJ_TUM, &tum_);
		open_trajectory("gt.kitti", MVOD_TRAJ_KITTI, &kitti_);
		if (o.format != "tum-mono") // monoVO's times.txt is its frame index, the layout's
			open_times(dir_ / "times.txt", times_);
		if (png_) {
			open_times(dir_ / "images" / "times.txt", image_times_);
		} else if (!dataset_) {
			const fs::path video = dir_ / "video.mkv";
			// Y800 (--codec raw) or FFV1, 8-bit grey either way, at exactly the calibration's
			// size, odd sides included (video.hpp: OpenCV's writer made them even).
			video_.open(video.string(), raw_, o.fps, cam.width, cam.height);
		}
	}

	~Output()
	{
		mvod_traj_writer_close(tum_);
		mvod_traj_writer_close(kitti_);
	}

	void add(double t, const Pose &pose, const cv::Mat &image)
	{
		if (png_) {
			char name[32];
			std::snprintf(name, sizeof name, "%06d.png", frames_);
			const fs::path file = dir_ / "images" / name;
			if (!cv::imwrite(file.string(), image))
				throw Failure(kExitFailure, "cannot write " + file.string());
		} else if (dataset_) {
			dataset_->add(t, pose, image);
		} else {
			video_.write(image);
		}
		if (times_.is_open())
			write_time(times_, t);
		if (png_)
			write_time(image_times_, t);

		mvod_pose p;
		for (int i = 0; i < 9; i++)
			p.R[i] = pose.R.val[i];
		for (int i = 0; i < 3; i++)
			p.t[i] = pose.t[i];
		mvod_traj_writer_add(tum_, t, &p);
		mvod_traj_writer_add(kitti_, t, &p);
		frames_++;
	}

	// Flushes and closes everything, reporting the first error any writer saw.
	void close()
	{
		video_.close();
		if (dataset_)
			dataset_->close();
		if (times_.is_open())
			close_times(dir_ / "times.txt", times_);
		if (png_)
			close_times(dir_ / "images" / "times.txt", image_times_);
		close_trajectory("gt.tum", &tum_);
		close_trajectory("gt.kitti", &kitti_);
	}

	// A whole file at once, through a temporary and rename().
	void write_file(const char *name, const std::string &text) const
	{
		const fs::path file = dir_ / name;
		const int rc = mvod_write_replace(file.c_str(), text.data(), text.size());
		if (rc < 0)
			throw Failure(kExitFailure, "cannot write " + file.string() + ": " + errno_text(rc));
	}

private:
	// Frames of an earlier, longer run would otherwise be read as part of this one.
	void remove_old_frames()
	{
		std::error_code ec;
		std::vector<fs::path> old;
		for (const fs::directory_entry &e : fs::directory_iterator(dir_ / "images", ec)) {
			const std::string name = e.path().filename().string();
			if (name.size() == 10 && name.compare(6, 4, ".png") == 0 && name.find_first_not_of("0123456789") == 6)
				old.push_back(e.path());
		}
		for (const fs::path &file : old)
			if (!ec)
				fs::remove(file, ec);
		if (ec)
			throw Failure(kExitFailure, "cannot clear old frames from " + (dir_ / "images").string() + ": " +
							    ec.message());
	}

	void save_calibration(const Camera &cam, const std::string &command_line)
	{
		mvod_camera c{};
		c.width = cam.width;
		c.height = cam.height;
		c.fx = cam.fx;
		c.fy = cam.fy;
		c.cx = cam.cx;
		c.cy = cam.cy;
		c.model = cam.fov ? MVOD_CAM_FOV : cam.fisheye ? MVOD_CAM_FISHEYE_KB4 : MVOD_CAM_PINHOLE_RADTAN;
		c.n_dist = int(cam.dist.size());
		std::copy(cam.dist.begin(), cam.dist.end(), c.dist);

		mvod_calib_meta meta{};
		meta.rms_px = -1;
		std::snprintf(meta.source, sizeof meta.source, "%s", command_line.c_str());
		std::snprintf(meta.board, sizeof meta.board, "%s", board_.c_str());
		if (command_line.size() >= sizeof meta.source) // cut, and say so
			std::memcpy(meta.source + sizeof meta.source - 4, "...", 4);

		const fs::path file = dir_ / "calib.json";
		const int rc = mvod_calib_save(file.c_str(), &c, &meta);
		if (rc < 0)
			throw Failure(kExitFailure, "cannot write " + file.string() + ": " + errno_text(rc));
	}

	void open_trajectory(const char *name, mvod_traj_format format, mvod_traj_writer **writer)
	{
		const fs::path file = dir_ / name;
		const int rc = mvod_traj_writer_open(file.c_str(), format, writer, nullptr, 0);
		if (rc < 0)
			throw Failure(kExitFailure, "cannot write " + file.string() + ": " + errno_text(rc));
	}

	void close_trajectory(const char *name, mvod_traj_writer **writer)
	{
		const int rc = mvod_traj_writer_close(*writer);
		*writer = nullptr;
		if (rc < 0)
			throw Failure(kExitFailure, "cannot write " + (dir_ / name).string() + ": " + errno_text(rc));
	}

	static void open_times(const fs::path &file, std::ofstream &out)
	{
		out.open(file);
		if (!out)
			throw Failure(kExitFailure, "cannot write " + file.string() + ": " + std::strerror(errno));
	}

	static void close_times(const fs::path &file, std::ofstream &out)
	{
		out.close();
		if (!out)
			throw Failure(kExitFailure, "cannot write " + file.string());
	}

	static void write_time(std::ofstream &out, double t)
	{
		char line[64];
		std::snprintf(line, sizeof line, "%.6f\n", t);
		out << line << std::flush; // whole lines only, like the trajectories, if the run is cut short
	}

	fs::path dir_;
	bool png_;
	bool raw_; // video.mkv uncompressed (--codec raw)
	std::string board_;
	VideoWriter video_; // video.mkv (--format mkv)
	std::unique_ptr<LayoutWriter> dataset_; // --format euroc, tum, tum-mono or kitti-raw
	std::ofstream times_, image_times_;
	mvod_traj_writer *tum_ = nullptr, *kitti_ = nullptr;
	int frames_ = 0;
};

// Blur (the lens), then noise (the sensor), then 8 bits.
void develop(cv::Mat &image, const Options &o, cv::RNG &rng, cv::Mat &grey)
{
	if (o.blur > 0)
		cv::GaussianBlur(image, image, cv::Size(), o.blur, o.blur, cv::BORDER_REFLECT_101);
	if (o.noise > 0) {
		cv::Mat noise(image.size(), CV_32F);
		rng.fill(noise, cv::RNG::NORMAL, 0.0, o.noise);
		image += noise;
	}
	image.convertTo(grey, CV_8U); // rounds and saturates
}

Trajectory make_trajectory(const Options &o)
{
	if (is_builtin_path(o.path))
		return builtin_path(o.path, o.frames > 0 ? o.frames : 60, o.fps, o.speed);
	// A bare word that is no file is a mistyped path name; anything else is a file to read.
	if (o.path.find_first_of("/.") == std::string::npos && access(o.path.c_str(), F_OK) != 0)
		usage_error("--path '" + o.path + "' is neither a built-in path (" + builtin_path_names() +
			    ") nor a pose file");
	return load_path(o.path, o.frames, o.fps);
}

double path_length(const Trajectory &tr)
{
	double length = 0;
	for (size_t i = 1; i < tr.poses.size(); i++)
		length += cv::norm(tr.poses[i].t - tr.poses[i - 1].t);
	return length;
}

void check_lens(const Renderer &renderer, const Options &o)
{
	if (renderer.worst_ray_error() > 0.01) {
		char message[160];
		std::snprintf(message, sizeof message,
			      "--%s: these coefficients fold the image over (some pixels have no ray; worst miss %.3g px)",
			      o.fov ? "fov" : o.fisheye ? "fisheye" : "distortion", renderer.worst_ray_error());
		usage_error(message);
	}
}

// The printed pattern: as many texels per square as fit a 4096-texel texture, up to 128 (at
// least 2 texels per image pixel for any board that fills less than the whole image), with a
// one-square quiet zone.
cv::Mat board_face(const mvod_board &board, const Options &o, int &px_per_square)
{
	int across, down;
	mvod_board_squares(&board, &across, &down);
	px_per_square = 128;
	while (px_per_square > 16 && (std::max(across, down) + 2) * px_per_square > 4096)
		px_per_square /= 2;
	mvod_image face{};
	const int rc = mvod_board_draw(&board, px_per_square, px_per_square, &face);
	if (rc < 0)
		throw Failure(kExitFailure, "cannot draw the board: " + errno_text(rc));
	cv::Mat image = cv::Mat(face.h, face.w, CV_8UC1, face.data, size_t(face.stride)).clone();
	mvod_board_image_free(&face);
	if (o.inverted)
		image = 255 - image;
	return image;
}

std::string format_pose(int view, const BoardPose &p)
{
	char line[256];
	std::snprintf(line, sizeof line, "%d %.17g %.17g %.17g %.17g %.17g %.17g\n", view, p.rvec[0], p.rvec[1], p.rvec[2],
		      p.t[0], p.t[1], p.t[2]);
	return line;
}

std::string format_corners(int view, const std::vector<cv::Point2d> &corners)
{
	std::string text;
	for (size_t id = 0; id < corners.size(); id++) {
		char line[96];
		std::snprintf(line, sizeof line, "%d %zu %.9f %.9f\n", view, id, corners[id].x, corners[id].y);
		text += line;
	}
	return text;
}

void run_board(const Options &o, const std::string &command_line)
{
	mvod_board board;
	char err[256];
	if (mvod_board_parse(o.board.c_str(), &board, err, sizeof err) < 0)
		usage_error(std::string("--board: ") + err);
	const Camera cam = camera_from(o);
	int pps;
	const cv::Mat face = board_face(board, o, pps);
	const double texel = board.square_m / pps;
	const World world = build_board_scene(face, pps * texel, texel, o.seed);
	Renderer renderer(world, cam);
	check_lens(renderer, o);
	const std::vector<BoardPose> poses =
		o.on_floor ? floor_poses(board, cam, o.floor, o.views, o.seed) : board_poses(board, cam, o.views, o.seed);

	Output out(o, cam, command_line);
	cv::RNG noise_rng(stream_seed(o.seed, 7));
	cv::Mat image, grey;
	std::string pose_text = "# view rx ry rz tx ty tz: board-to-camera, X_cam = R(r) X_board + t, metres\n";
	std::string corner_text = "# view corner u v: exact pixel position (pixel centres at integers)\n";
	for (size_t i = 0; i < poses.size(); i++) {
		const Pose camera = poses[i].camera_to_board();
		renderer.render(camera, image);
		develop(image, o, noise_rng, grey);
		out.add(double(i) / o.fps, camera, grey);
		pose_text += format_pose(int(i), poses[i]);
		corner_text += format_corners(int(i), project_corners(board, cam, poses[i]));
	}
	out.write_file("board_poses.txt", pose_text);
	out.write_file("corners.txt", corner_text);
	out.close();
	std::printf("mvod-synth: %zu views of %s, %dx%d, %d texels per square, written to %s\n", poses.size(),
		    o.board.c_str(), cam.width, cam.height, pps, o.out.c_str());
}

void run(const Options &o, const std::string &command_line)
{
	if (!o.board.empty())
		return run_board(o, command_line);
	const Trajectory path = make_trajectory(o);
	const Camera cam = camera_from(o);

	// The street heads where the first camera looks when the path itself does not move.
	const cv::Vec3d heading(path.poses[0].R(0, 2), 0, path.poses[0].R(2, 2));
	const Skeleton skeleton(path.skeleton, path.closed, cv::norm(heading) > 0 ? cv::normalize(heading) : cv::Vec3d(0, 0, 1));
	std::vector<cv::Vec3d> cameras;
	for (const Pose &p : path.poses)
		cameras.push_back(p.t);
	const World world = build_street(skeleton, cameras, o.seed);

	Renderer renderer(world, cam);
	check_lens(renderer, o);

	Output out(o, cam, command_line);
	cv::RNG noise_rng(stream_seed(o.seed, 7));
	cv::Mat image, grey;
	for (size_t i = 0; i < path.poses.size(); i++) {
		renderer.render(path.poses[i], image);
		develop(image, o, noise_rng, grey);
		out.add(path.times[i], path.poses[i], grey);
	}
	out.close();

	std::printf("mvod-synth: %zu frames, %dx%d, path %.2f m, written to %s\n", path.poses.size(), cam.width, cam.height,
		    path_length(path), o.out.c_str());
}

} // namespace

int main(int argc, char **argv)
{
	std::string command_line = "mvod-synth";
	for (int i = 1; i < argc; i++)
		command_line += " " + quote(argv[i]);

	try {
		run(parse_options(argc, argv), command_line);
	} catch (const Failure &f) {
		std::fprintf(stderr, "mvod-synth: %s\n", f.what());
		return f.status;
	} catch (const std::exception &e) { // OpenCV errors, out of memory
		std::fprintf(stderr, "mvod-synth: %s\n", e.what());
		return kExitFailure;
	}
	return 0;
}
