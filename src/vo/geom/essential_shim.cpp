#include "essential_shim.h"

#include <cerrno>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "util/shim_guard.hpp"

extern "C" int mvod_essential_find(const double *x1, const double *x2, int n, bool magsac,
				   double thresh, double conf, double E[9], uint8_t *mask, int *n_inliers)
{
	if (n < 5)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat m1(n, 2, CV_64F, const_cast<double *>(x1));
		cv::Mat m2(n, 2, CV_64F, const_cast<double *>(x2));
		cv::Mat msk(n, 1, CV_8U, mask);
		int method = magsac ? cv::USAC_MAGSAC : cv::RANSAC;
		cv::Mat e = cv::findEssentialMat(m1, m2, cv::Matx33d::eye(), method, conf, thresh, msk);
		/* Several solutions come back stacked; RANSAC has already picked the best first. */
		if (e.rows < 3 || e.cols != 3)
			return -ENODATA;
		for (int i = 0; i < 9; i++)
			E[i] = e.at<double>(i / 3, i % 3);
		*n_inliers = cv::countNonZero(msk);
		return 0;
	});
}

extern "C" int mvod_essential_decompose(const double E[9], double R1[9], double R2[9], double t[3])
{
	return mvod_guarded([&] {
		cv::Matx33d e(E), r1, r2;
		cv::Vec3d tv;
		cv::decomposeEssentialMat(e, r1, r2, tv);
		for (int i = 0; i < 9; i++) {
			R1[i] = r1.val[i];
			R2[i] = r2.val[i];
		}
		for (int i = 0; i < 3; i++)
			t[i] = tv[i];
		return 0;
	});
}
