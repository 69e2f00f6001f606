/*
 * For *_shim.cpp only: the one way an extern "C" body turns C++ exceptions into -errno. Plain
 * standard C++, so shims on any library use it; included after OpenCV it also maps OpenCV's
 * out-of-memory exception to -ENOMEM.
 */
#ifndef MVOD_SHIM_GUARD_HPP
#define MVOD_SHIM_GUARD_HPP

#include <cerrno>
#include <exception>
#include <new>

/*
 * Runs body (returning 0 or -errno); no exception ever crosses into C: out of memory is
 * -ENOMEM, any other exception (a library's error, std::exception or not) -EIO.
 */
template <typename F> static inline int mvod_guarded(F &&body) noexcept
{
	try {
		return body();
	} catch (const std::bad_alloc &) {
		return -ENOMEM;
#ifdef CV_VERSION
	} catch (const cv::Exception &e) {
		/*
		 * A shim that includes OpenCV (before this file) gets this case: OpenCV's own
		 * allocator throws cv::Exception StsNoMem, not std::bad_alloc, when memory runs out.
		 */
		return e.code == cv::Error::StsNoMem ? -ENOMEM : -EIO;
#endif
	} catch (const std::exception &) {
		return -EIO;
	} catch (...) {
		return -EIO;
	}
}

#endif
