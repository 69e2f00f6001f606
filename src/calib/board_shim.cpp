/* Board drawing: OpenCV's aruco module draws ChArUco patterns exactly as its detector expects. */
#include "mvod/board.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "util/shim_guard.hpp"

namespace {

cv::Mat draw_pattern(const mvod_board &b, int pps)
{
	int across, down;
	mvod_board_squares(&b, &across, &down);
	cv::Size size(across * pps, down * pps);
	cv::Mat img;
	if (b.kind == MVOD_BOARD_CHARUCO) {
		auto dict = cv::aruco::getPredefinedDictionary(b.dict);
		auto board = cv::aruco::CharucoBoard::create(b.cols, b.rows, (float)b.square_m,
							     (float)b.marker_m, dict);
		board->draw(size, img, 0, 1);
		return img;
	}
	/* The top-left square is black, as in OpenCV's pattern.png. */
	img = cv::Mat(size, CV_8UC1, cv::Scalar(255));
	for (int y = 0; y < down; y++)
		for (int x = 0; x < across; x++)
			if ((x + y) % 2 == 0)
				img(cv::Rect(x * pps, y * pps, pps, pps)).setTo(0);
	return img;
}

} // namespace

extern "C" int mvod_board_draw(const struct mvod_board *b, int px_per_square, int margin_px,
			       struct mvod_image *out)
{
	std::memset(out, 0, sizeof(*out));
	if (px_per_square < 4 || margin_px < 0 || px_per_square > 4096 || margin_px > 65536)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat pat = draw_pattern(*b, px_per_square);
		int w = pat.cols + 2 * margin_px, h = pat.rows + 2 * margin_px;
		auto *data = static_cast<uint8_t *>(std::malloc((size_t)w * h));
		if (!data)
			return -ENOMEM;
		cv::Mat dst(h, w, CV_8UC1, data);
		dst.setTo(255);
		pat.copyTo(dst(cv::Rect(margin_px, margin_px, pat.cols, pat.rows)));
		*out = {w, h, w, MVOD_PIX_GREY, data};
		return 0;
	});
}

extern "C" void mvod_board_image_free(struct mvod_image *img)
{
	std::free(img->data);
	img->data = nullptr;
}

extern "C" int mvod_board_caption(struct mvod_image *img, int margin_px, const char *text)
{
	/* A quarter of the zone below the pattern, in mid grey: readable, and not a black edge a
	 * detector would take for part of the board. */
	const int font = cv::FONT_HERSHEY_SIMPLEX;
	const double grey = 110;
	if (margin_px < 12 || img->fmt != MVOD_PIX_GREY)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat dst(img->h, img->w, CV_8UC1, img->data, (size_t)img->stride);
		int base = 0;
		cv::Size one = cv::getTextSize(text, font, 1.0, 1, &base);
		double scale = std::min(margin_px / 4.0 / one.height, (img->w - 2.0 * margin_px) / one.width);
		int thick = std::max(1, (int)std::lround(scale * 1.5));
		cv::Size ts = cv::getTextSize(text, font, scale, thick, &base);
		cv::Point org((img->w - ts.width) / 2, img->h - margin_px / 2 + ts.height / 2);
		cv::putText(dst, text, org, font, scale, cv::Scalar(grey), thick, cv::LINE_AA);
		return 0;
	});
}
