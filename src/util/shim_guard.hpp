/* For *_shim.cpp only: the one way an extern "C" body turns C++ exceptions into -errno. */
#ifndef MVOD_SHIM_GUARD_HPP
#define MVOD_SHIM_GUARD_HPP

#include <cerrno>
#include <new>

#include <opencv2/core.hpp>

/* Runs body (returning 0 or -errno); no exception ever crosses into C. */
template <typename F> static inline int mvod_guarded(F &&body) noexcept
{
	try {
		return body();
	} catch (const std::bad_alloc &) {
		return -ENOMEM;
	} catch (const cv::Exception &e) {
		/* OpenCV's own allocator throws this, not std::bad_alloc, when memory runs out. */
		return e.code == cv::Error::StsNoMem ? -ENOMEM : -EIO;
	} catch (...) {
		return -EIO;
	}
}

#endif
