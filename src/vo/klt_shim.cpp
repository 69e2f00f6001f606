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
	cv::TermCriteria crit;
};

extern "C" int mvod_klt_cv_create(int width, int height, int win, int levels, int iterations,
				  double eps_px, int fast_cap, struct mvod_klt_cv **out)
{
	if (width < 1 || height < 1 || win < 3 || levels < 0 || iterations < 1 || !(eps_px > 0) ||
	    fast_cap < 1)
		return -EINVAL;
	return mvod_guarded([&] {
		auto k = std::make_unique<mvod_klt_cv>();
		k->w = width;
		k->h = height;
		k->levels = levels;
		k->fast_cap = fast_cap;
		k->win = cv::Size(win, win);
		k->crit = cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, iterations,
					   eps_px);
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
		 * withDerivatives (true) stores each level's Scharr derivatives after it, so
		 * calcOpticalFlowPyrLK reads them instead of recomputing them for its "prev" pyramid
		 * on every call: once per frame, 3.7e6 instructions per frame (callgrind, KITTI 06).
		 */
		cv::buildOpticalFlowPyramid(view(grey), k->newest, k->win, k->levels, true,
					    cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
		k->have = k->have < 2 ? k->have + 1 : 2;
		return 0;
	});
}

extern "C" int mvod_klt_cv_flow(struct mvod_klt_cv *k, int backward, int win, int levels,
				const float *from, float *to, int n, uint8_t *ok)
{
	if (k->have < 2 || n < 0 || win < 3 || win > k->win.width || levels < 0 || levels > k->levels)
		return -EINVAL;
	if (n == 0)
		return 0;
	return mvod_guarded([&] {
		cv::Mat a(n, 1, CV_32FC2, const_cast<float *>(from)), b(n, 1, CV_32FC2, to);
		cv::Mat st(n, 1, CV_8UC1, ok);
		const std::vector<cv::Mat> &p0 = backward ? k->newest : k->older;
		const std::vector<cv::Mat> &p1 = backward ? k->older : k->newest;
		cv::calcOpticalFlowPyrLK(p0, p1, a, b, st, cv::noArray(), cv::Size(win, win), levels,
					 k->crit, cv::OPTFLOW_USE_INITIAL_FLOW);
		return 0;
	});
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
