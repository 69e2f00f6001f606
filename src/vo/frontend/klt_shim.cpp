#include "klt_shim.h"

#include <cerrno>
#include <memory>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/video/tracking.hpp>

#include "util/shim_guard.hpp"

/*
 * A pyramid: OpenCV's levels (buildOpticalFlowPyramid re-creates each with Mat::create, which
 * keeps a buffer of the same size, so after the second frame they are built in place) and each
 * level's Scharr derivatives, (d/dx, d/dy) pairs with the levels' border, zero in it (sized at
 * create).
 */
struct pyramid {
	std::vector<cv::Mat> img;
	std::vector<std::vector<int16_t>> deriv;
};

struct mvod_klt_cv {
	int w, h, levels, fast_cap;
	cv::Size win;
	pyramid older, newest; /* swapped frame to frame */
	std::vector<int16_t> tmp; /* mvod_lk_scharr's two rows */
	int have; /* pyramids built so far, up to 2 */
	std::vector<cv::KeyPoint> corners;
};

/* Level l's width or height from level 0's, as buildOpticalFlowPyramid halves them. */
static int level_size(int n, int l)
{
	for (; l > 0; l--)
		n = (n + 1) / 2;
	return n;
}

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
		for (pyramid *p : {&k->older, &k->newest})
			for (int l = 0; l <= levels; l++)
				p->deriv.emplace_back(2 * (size_t)(level_size(width, l) + 2 * win) *
						      (size_t)(level_size(height, l) + 2 * win));
		k->tmp.resize(2 * ((size_t)width + 2));
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
		 * The derivatives are lk.c's (OpenCV's values to the bit, 16 pixels a vector with
		 * AVX2): once per frame, 3.9e6 -> 1.4e6 instructions per frame on KITTI 06
		 * (BENCHMARKS.md, "Own Lucas-Kanade").
		 */
		cv::buildOpticalFlowPyramid(view(grey), k->newest.img, k->win, k->levels, false,
					    cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
		int b = k->win.width;
		for (size_t l = 0; l < k->newest.img.size(); l++) {
			const cv::Mat &img = k->newest.img[l];
			ptrdiff_t dstride = 2 * (ptrdiff_t)(img.cols + 2 * b);
			mvod_lk_scharr(img.ptr<uint8_t>(), (ptrdiff_t)img.step, img.cols, img.rows,
				       k->newest.deriv[l].data() + b * dstride + 2 * b, dstride,
				       k->tmp.data());
		}
		k->have = k->have < 2 ? k->have + 1 : 2;
		return 0;
	});
}

extern "C" int mvod_klt_cv_levels(const struct mvod_klt_cv *k, int newest,
				  struct mvod_lk_level *out, int max)
{
	const pyramid &p = newest ? k->newest : k->older;
	int n = std::min((int)p.img.size(), max), b = k->win.width;
	for (int l = 0; l < n; l++) {
		const cv::Mat &img = p.img[(size_t)l];
		ptrdiff_t dstride = 2 * (ptrdiff_t)(img.cols + 2 * b);
		out[l] = mvod_lk_level{img.ptr<uint8_t>(),
				       p.deriv[(size_t)l].data() + b * dstride + 2 * b,
				       (ptrdiff_t)img.step,
				       dstride,
				       img.cols,
				       img.rows,
				       b};
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
		/* Lucas-Kanade maps level l to level 0 by 2^l, and so does this. */
		cv::FAST(k->newest.img[(size_t)level], k->corners, threshold, true);
		corners_out(k, (float)(1 << level), xy, n);
		return 0;
	});
}
