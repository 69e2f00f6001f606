#include "svd_shim.h"

#include <opencv2/core.hpp>

#include "util/shim_guard.hpp"

extern "C" int mvod_svd3(const double A[9], double U[9], double S[3], double Vt[9])
{
	return mvod_guarded([&] {
		cv::Matx33d a(A), u, vt;
		cv::Vec3d s;
		cv::SVD::compute(a, s, u, vt, cv::SVD::FULL_UV);
		for (int i = 0; i < 9; i++) {
			U[i] = u.val[i];
			Vt[i] = vt.val[i];
		}
		for (int i = 0; i < 3; i++)
			S[i] = s[i];
		return 0;
	});
}
