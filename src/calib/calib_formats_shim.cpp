/* OpenCV FileStorage YAML/XML and ROS camera_info YAML, read and written with cv::FileStorage. */
#include "mvod/calib.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/calib_internal.h"
#include "util/atomic_file.h"
#include "util/errbuf.h"
#include "util/shim_guard.hpp"

namespace {

/* FileStorage refuses YAML without OpenCV's own header line; ROS files never have it. */
bool has_opencv_syntax(const char *text)
{
	const char *p = text + std::strspn(text, " \t\r\n");
	return std::strncmp(p, "%YAML:", 6) == 0 || *p == '<';
}

/* A line of only spaces, tabs and a carriage return (len bytes at p). */
bool blank(const char *p, size_t len)
{
	return std::strspn(p, " \t\r") >= len;
}

/*
 * Whether YAML text has the shape of every calibration file: directives ("%YAML:1.0"), an
 * optional "---" line, then a map whose keys start lines (with a letter or '_'); deeper
 * lines indented. OpenCV 4.6's YAML parser loops forever when its top-level collection ends
 * before the end of the text and a line starting with '-' follows (fuzzing found
 * " -L-\n-\n " and "...\n-x"): text of another shape never reaches it.
 */
bool yaml_shape_ok(const char *text)
{
	bool header = true;
	for (const char *p = text; *p;) {
		size_t len = std::strcspn(p, "\n");
		if (!blank(p, len) && p[0] != '#') {
			bool directive = header && (p[0] == '%' ||
						    (std::strncmp(p, "---", 3) == 0 && blank(p + 3, len - 3)));
			if (!directive && (header || p[0] != ' ') && !std::isalpha((unsigned char)p[0]) &&
			    p[0] != '_')
				return false;
			header = directive;
		}
		p += len + (p[len] == '\n');
	}
	return true;
}

/* A matrix node: rows, cols and rows*cols finite numbers in data. Both OpenCV's
 * !!opencv-matrix (and its XML twin) and ROS's plain maps have this shape. */
int read_matrix(const cv::FileNode &node, const char *key, int &rows, int &cols, std::vector<double> &v,
		char *err, size_t errlen)
{
	if (node.empty() || node.isNone())
		return mvod_errf(err, errlen, -EINVAL, "no \"%s\" key", key);
	if (!node.isMap() || !node["rows"].isInt() || !node["cols"].isInt() || !node["data"].isSeq())
		return mvod_errf(err, errlen, -EINVAL, "\"%s\" must be a matrix with rows, cols and data",
				 key);
	rows = (int)node["rows"];
	cols = (int)node["cols"];
	const cv::FileNode data = node["data"];
	if (rows < 0 || cols < 0 || (size_t)rows * (size_t)cols != data.size())
		return mvod_errf(err, errlen, -EINVAL, "\"%s\": data holds %zu numbers, not rows x cols = %d x %d",
				 key, data.size(), rows, cols);
	v.clear();
	for (const cv::FileNode &x : data) {
		if (!x.isInt() && !x.isReal())
			return mvod_errf(err, errlen, -EINVAL, "\"%s\": entry %zu is not a number", key, v.size());
		v.push_back((double)x);
		if (!std::isfinite(v.back()))
			return mvod_errf(err, errlen, -EINVAL, "\"%s\": entry %zu is not finite", key, v.size() - 1);
	}
	return 0;
}

int read_size(const cv::FileStorage &fs, const char *key, int &out, char *err, size_t errlen)
{
	const cv::FileNode n = fs[key];
	if (n.empty() || n.isNone())
		return 0;
	if (!n.isInt() || (int)n < 0 || (int)n > 65535)
		return mvod_errf(err, errlen, -EINVAL, "\"%s\" must be a whole number of pixels", key);
	out = (int)n;
	return 0;
}

/* ROS names, Kalibr's and mvod's own. */
int read_model(const cv::FileStorage &fs, mvod_cam_model &model, char *err, size_t errlen)
{
	const cv::FileNode n = fs["distortion_model"];
	if (n.empty() || n.isNone())
		return 0;
	const std::string name = n.isString() ? (std::string)n : "";
	if (name == "plumb_bob" || name == "rational_polynomial" || name == "radtan" || name == "pinhole-radtan")
		model = MVOD_CAM_PINHOLE_RADTAN;
	else if (name == "equidistant" || name == "fisheye" || name == "fisheye-kb4")
		model = MVOD_CAM_FISHEYE_KB4;
	else
		return mvod_errf(err, errlen, -EINVAL,
				 "\"distortion_model\" must be plumb_bob, rational_polynomial, equidistant or fisheye");
	return 0;
}

int read_camera(const cv::FileStorage &fs, mvod_camera &c, char *err, size_t errlen)
{
	/* OpenCV's stereo_calib sample writes M1 D1 M2 D2: the first camera is the one wanted. */
	const bool stereo = fs["camera_matrix"].isNone() && !fs["M1"].isNone();
	const char *kkey = stereo ? "M1" : "camera_matrix", *dkey = stereo ? "D1" : "distortion_coefficients";
	int rows, cols, ret;
	std::vector<double> v;
	if ((ret = read_size(fs, "image_width", c.width, err, errlen)) ||
	    (ret = read_size(fs, "image_height", c.height, err, errlen)) ||
	    (ret = read_model(fs, c.model, err, errlen)))
		return ret;
	if (fs["camera_matrix"].isNone() && !stereo)
		return mvod_errf(err, errlen, -EINVAL,
				 "unknown calibration format: no \"camera_matrix\" key, so not OpenCV or ROS "
				 "YAML (mvod also reads mvod JSON, [K, dist] JSON and KITTI calib.txt)");
	if ((ret = read_matrix(fs[kkey], kkey, rows, cols, v, err, errlen)))
		return ret;
	if (rows != 3 || cols != 3 || mvod_calib_set_K(v.data(), &c) != 0)
		return mvod_errf(err, errlen, -EINVAL,
				 "\"%s\" must be 3x3 [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0", kkey);
	if ((ret = read_matrix(fs[dkey], dkey, rows, cols, v, err, errlen)))
		return ret;
	if ((rows > 1 && cols > 1) || !mvod_calib_dist_count_ok(c.model, (int)v.size()))
		return mvod_errf(err, errlen, -EINVAL, "\"%s\" must be 1xN or Nx1 with N = %s for %s (not %dx%d)",
				 dkey, mvod_calib_dist_counts(c.model), mvod_cam_model_name(c.model), rows, cols);
	c.n_dist = (int)v.size();
	std::copy(v.begin(), v.end(), c.dist);
	return 0;
}

void write_matrix(cv::FileStorage &fs, const char *key, int rows, int cols, const double *v)
{
	fs << key << cv::Mat(rows, cols, CV_64F, const_cast<double *>(v));
}

} // namespace

extern "C" int mvod_calib_parse_filestorage(const char *text, struct mvod_camera *cam,
					    enum mvod_calib_format *fmt, char *err, size_t errlen)
{
	const bool opencv = has_opencv_syntax(text);
	if (*(text + std::strspn(text, " \t\r\n")) != '<' && !yaml_shape_ok(text))
		return mvod_errf(err, errlen, -EINVAL, "malformed OpenCV/ROS calibration file: "
				 "expected a map of keys (camera_matrix: ...), each at the start of a line");
	int ret = mvod_guarded([&] {
		cv::FileStorage fs;
		try {
			fs.open(opencv ? std::string(text) : "%YAML:1.0\n" + std::string(text),
				cv::FileStorage::READ | cv::FileStorage::MEMORY);
		} catch (const cv::Exception &) {
			/* FileStorage throws on syntax errors; its message spans lines and names its source. */
		}
		if (!fs.isOpened())
			return mvod_errf(err, errlen, -EINVAL,
					 "unknown calibration format: not mvod JSON, a [K, dist] JSON pair, KITTI "
					 "calib.txt, OpenCV YAML/XML or ROS camera_info YAML");
		mvod_camera c{};
		c.model = MVOD_CAM_PINHOLE_RADTAN;
		int r = read_camera(fs, c, err, errlen);
		if (r == 0)
			*cam = c;
		return r;
	});
	if (ret == -EIO) /* an exception from a file whose structure FileStorage did not expect */
		return mvod_errf(err, errlen, -EINVAL, "malformed OpenCV/ROS calibration file");
	if (ret == 0 && fmt)
		*fmt = opencv ? MVOD_CALIB_FMT_OPENCV : MVOD_CALIB_FMT_ROS;
	return ret;
}

extern "C" int mvod_calib_save_opencv(const char *path, const struct mvod_camera *cam, char *err, size_t errlen)
{
	const size_t n = std::strlen(path);
	const bool xml = n >= 4 && std::strcmp(path + n - 4, ".xml") == 0;
	std::string text;
	int ret = mvod_guarded([&] {
		/* With MEMORY, the name only picks the syntax. */
		cv::FileStorage fs(xml ? ".xml" : ".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
		if (cam->width > 0 && cam->height > 0) {
			fs << "image_width" << cam->width;
			fs << "image_height" << cam->height;
		}
		const double K[9] = {cam->fx, 0, cam->cx, 0, cam->fy, cam->cy, 0, 0, 1};
		const double zero[5] = {0, 0, 0, 0, 0};
		write_matrix(fs, "camera_matrix", 3, 3, K);
		/* No coefficients is written as OpenCV's usual five zeros. */
		write_matrix(fs, "distortion_coefficients", 1, cam->n_dist ? cam->n_dist : 5,
			     cam->n_dist ? cam->dist : zero);
		if (cam->model == MVOD_CAM_FISHEYE_KB4)
			fs << "distortion_model" << "fisheye";
		text = fs.releaseAndGetString();
		return 0;
	});
	if (ret == 0)
		ret = mvod_write_replace(path, text.data(), text.size());
	if (ret)
		mvod_errf(err, errlen, ret, "cannot write %s: %s", path, std::strerror(-ret));
	return ret;
}
