#include "klt_shim.h"

#include <cerrno>
#include <memory>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/video/tracking.hpp>

#include "util/shim_guard.hpp"

struct mvod_klt_cv {
	int w, h, levels, fast_cap;
	cv::Size win;
	/*
	 * Two pyramids swapped frame to frame: buildOpticalFlowPyramid re-creates each level
	 * with Mat::create, which keeps a buffer of the same size, so after the second frame
	 * the pyramids are built in place.
	 */
	std::vector<cv::Mat> older, newest;
	int have; /* pyramids built so far, up to 2 */
	std::vector<cv::KeyPoint> corners;
};

extern "C" int mvod_klt_cv_create(int width, int height, int win, int levels, int fast_cap,
				  struct mvod_klt_cv **out)
{
	if (width < 1 || height < 1 || win < 3 || levels < 0 || fast_cap < 1)
		return -EINVAL;
	return mvod_guarded([&] {
		auto k = std::make_unique<mvod_klt_cv>();
		k->w = width;
		k->h = height;
		k->levels = levels;
		k->fast_cap = fast_cap;
		k->win = cv::Size(win, win);
		k->corners.reserve((size_t)fast_cap);
		*out = k.release();
		return 0;
	});
}

extern "C" void mvod_klt_cv_destroy(struct mvod_klt_cv *k)
{
	delete k;
}

static cv::Mat view(const struct mvod_image *img)
{
	return cv::Mat(img->h, img->w, CV_8UC1, img->data, (size_t)img->stride);
}

extern "C" int mvod_klt_cv_push(struct mvod_klt_cv *k, const struct mvod_image *grey)
{
	if (grey->fmt != MVOD_PIX_GREY || grey->w != k->w || grey->h != k->h)
		return -EINVAL;
	return mvod_guarded([&] {
		std::swap(k->older, k->newest);
		/*
		 * Not reusing the input: level 0 is a copy, since the caller reuses grey's buffer.
		 * withDerivatives (true) stores each level's Scharr derivatives after it, which
		 * lk.c reads as the template's: computed once per frame, 3.7e6 instructions per
		 * frame (callgrind, KITTI 06).
		 */
		cv::buildOpticalFlowPyramid(view(grey), k->newest, k->win, k->levels, true,
					    cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
		k->have = k->have < 2 ? k->have + 1 : 2;
		return 0;
	});
}

extern "C" int mvod_klt_cv_levels(const struct mvod_klt_cv *k, int newest,
				  struct mvod_lk_level *out, int max)
{
	const std::vector<cv::Mat> &p = newest ? k->newest : k->older;
	int n = std::min((int)p.size() / 2, max);
	for (int l = 0; l < n; l++) {
		const cv::Mat &img = p[(size_t)(2 * l)], &d = p[(size_t)(2 * l + 1)];
		out[l] = mvod_lk_level{img.ptr<uint8_t>(), d.ptr<int16_t>(), (ptrdiff_t)img.step,
				       (ptrdiff_t)(d.step / sizeof(int16_t)), img.cols, img.rows,
				       k->win.width};
	}
	return k->have < (newest ? 1 : 2) ? 0 : n;
}

/* k->corners' first fast_cap positions into xy, times scale; *n: how many. */
static void corners_out(struct mvod_klt_cv *k, float scale, float *xy, int *n)
{
	int m = std::min((int)k->corners.size(), k->fast_cap);
	for (int i = 0; i < m; i++) {
		xy[2 * i] = k->corners[(size_t)i].pt.x * scale;
		xy[2 * i + 1] = k->corners[(size_t)i].pt.y * scale;
	}
	*n = m;
}

extern "C" int mvod_klt_cv_fast(struct mvod_klt_cv *k, const struct mvod_image *grey, int threshold,
				float *xy, int *n)
{
	if (grey->fmt != MVOD_PIX_GREY)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::FAST(view(grey), k->corners, threshold, true);
		corners_out(k, 1, xy, n);
		return 0;
	});
}

extern "C" int mvod_klt_cv_fast_level(struct mvod_klt_cv *k, int level, int threshold, float *xy,
				      int *n)
{
	if (k->have < 1 || level < 0 || level > k->levels)
		return -EINVAL;
	return mvod_guarded([&] {
		/*
		 * A pyramid built with derivatives holds level l's image at 2l (its derivatives at
		 * 2l + 1); Lucas-Kanade maps level l to level 0 by 2^l, and so does this.
		 */
		cv::FAST(k->newest[(size_t)(2 * level)], k->corners, threshold, true);
		corners_out(k, (float)(1 << level), xy, n);
		return 0;
	});
}
