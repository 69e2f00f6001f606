/*
 * For *_shim.cpp only: the one way an extern "C" body turns C++ exceptions into -errno. Plain
 * standard C++, so shims on any library use it (OpenCV's cv::Exception is a std::exception).
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
	} catch (const std::exception &) {
		return -EIO;
	} catch (...) {
		return -EIO;
	}
}

#endif
