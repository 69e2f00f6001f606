/* OpenCV FileStorage YAML/XML, written with cv::FileStorage (calib_filestorage.c reads it). */
#include "mvod/calib.h"

#include <cerrno>
#include <cstring>
#include <string>

#include <opencv2/core.hpp>

#include "util/atomic_file.h"
#include "util/errbuf.h"
#include "util/shim_guard.hpp"

namespace {

void write_matrix(cv::FileStorage &fs, const char *key, int rows, int cols, const double *v)
{
	fs << key << cv::Mat(rows, cols, CV_64F, const_cast<double *>(v));
}

} // namespace

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
		double K[9];
		mvod_camera_K(cam, K);
		const double zero[5] = {0, 0, 0, 0, 0};
		write_matrix(fs, "camera_matrix", 3, 3, K);
		/* No coefficients is written as OpenCV's usual five zeros. */
		write_matrix(fs, "distortion_coefficients", 1, cam->n_dist ? cam->n_dist : 5,
			     cam->n_dist ? cam->dist : zero);
		/* OpenCV's own files cannot name a model: mvod's key says which, as ROS's does. */
		if (cam->model == MVOD_CAM_FISHEYE_KB4)
			fs << "distortion_model" << "fisheye";
		else if (cam->model == MVOD_CAM_FOV)
			fs << "distortion_model" << "fov";
		/* Flat scalars, as calib_filestorage.c reads them and mvod mount writes them. */
		if (cam->has_mount) {
			fs << "mount_height_m" << cam->mount_height_m;
			fs << "mount_pitch_deg" << cam->mount_pitch_deg;
			fs << "mount_roll_deg" << cam->mount_roll_deg;
		}
		text = fs.releaseAndGetString();
		return 0;
	});
	if (ret == 0)
		ret = mvod_write_replace(path, text.data(), text.size());
	if (ret)
		mvod_errf(err, errlen, ret, "cannot write %s: %s", path, std::strerror(-ret));
	return ret;
}
