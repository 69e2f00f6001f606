#include "lk_opencv.h"

#include <cerrno>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/video/tracking.hpp>

extern "C" int lk_opencv_flow(const uint8_t *I, const uint8_t *J, int w, int h, ptrdiff_t stride,
			      const struct mvod_lk_params *p, const float *from, float *to, int n,
			      uint8_t *status)
{
	try {
		cv::Mat i(h, w, CV_8UC1, const_cast<uint8_t *>(I), (size_t)stride);
		cv::Mat j(h, w, CV_8UC1, const_cast<uint8_t *>(J), (size_t)stride);
		std::vector<cv::Point2f> a((size_t)n), b((size_t)n);
		for (int k = 0; k < n; k++) {
			a[(size_t)k] = cv::Point2f(from[2 * k], from[2 * k + 1]);
			b[(size_t)k] = cv::Point2f(to[2 * k], to[2 * k + 1]);
		}
		std::vector<uchar> st;
		std::vector<float> err;
		cv::calcOpticalFlowPyrLK(
			i, j, a, b, st, err, cv::Size(p->win, p->win), p->levels,
			cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
					 p->iterations, (double)p->eps_px),
			cv::OPTFLOW_USE_INITIAL_FLOW, 1e-4);
		for (int k = 0; k < n; k++) {
			to[2 * k] = b[(size_t)k].x;
			to[2 * k + 1] = b[(size_t)k].y;
			status[k] = st[(size_t)k];
		}
		return 0;
	} catch (...) {
		return -EIO;
	}
}
