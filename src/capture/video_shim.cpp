#include "video_shim.h"

#include <cerrno>
#include <climits>
#include <cmath>
#include <memory>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "capture/png_grey.h"
#include "util/shim_guard.hpp"


/* A view of m, valid while m keeps its buffer. */
static int view_of(cv::Mat &m, struct mvod_image *img)
{
	if (m.type() != CV_8UC1 && m.type() != CV_8UC3)
		return -ENOTSUP;
	*img = {m.cols, m.rows, (int)m.step[0], m.channels() == 1 ? MVOD_PIX_GREY : MVOD_PIX_BGR,
		m.data};
	return 0;
}

/*
 * cv::imdecode leaves its destination untouched when the data is no image, so the only sure
 * sign of failure is a destination that was empty before and is empty after. This allocator
 * lets the destination be emptied before every decode yet get the same pixel buffer back
 * from Mat::create while the shape holds, so steady state does not allocate pixels.
 */
class KeepAllocator : public cv::MatAllocator {
public:
	cv::Mat kept; /* the last decoded image; shares its buffer with the destination */

	cv::UMatData *allocate(int dims, const int *sizes, int type, void *data, size_t *step,
			       cv::AccessFlag flags, cv::UMatUsageFlags usage) const override
	{
		if (!data && dims == 2 && !kept.empty() && sizes[0] == kept.rows &&
		    sizes[1] == kept.cols && type == kept.type()) {
			step[0] = kept.step[0];
			step[1] = kept.step[1];
			return kept.u; /* Mat::create adds the reference */
		}
		return std_alloc->allocate(dims, sizes, type, data, step, flags, usage);
	}
	bool allocate(cv::UMatData *u, cv::AccessFlag flags, cv::UMatUsageFlags usage) const override
	{
		return std_alloc->allocate(u, flags, usage);
	}
	/* Buffers always come from the standard allocator, which frees them. */
	void deallocate(cv::UMatData *u) const override
	{
		std_alloc->deallocate(u);
	}

private:
	cv::MatAllocator *std_alloc = cv::Mat::getStdAllocator();
};

struct mvod_imgdec {
	KeepAllocator alloc; /* declared first: outlives img */
	cv::Mat img;
	/*
	 * Pixels as stored (no EXIF rotation: calibration and VO want the sensor's layout); the
	 * first image then fixes grey or colour for the rest of the sequence.
	 */
	int flags = cv::IMREAD_ANYCOLOR | cv::IMREAD_IGNORE_ORIENTATION;
	struct mvod_png *png = nullptr; /* 8-bit grey PNGs: decoded without OpenCV */

	~mvod_imgdec() { mvod_png_destroy(png); }
};

extern "C" int mvod_imgdec_create(struct mvod_imgdec **out)
{
	return mvod_guarded([&] {
		auto d = std::make_unique<mvod_imgdec>();
		d->img.allocator = &d->alloc;
		int ret = mvod_png_create(&d->png);
		if (ret)
			return ret;
		*out = d.release();
		return 0;
	});
}

/*
 * An 8-bit grey PNG decoded by png_grey.c into d->img's buffer (kept while the size holds),
 * unless the sequence is colour (its first image was): 0, or -errno to leave it to imdecode,
 * which then also reports a corrupt image.
 */
static int grey_png(struct mvod_imgdec *d, const uint8_t *buf, size_t len)
{
	int w, h;
	if ((d->flags & cv::IMREAD_COLOR) || mvod_png_grey_size(buf, len, &w, &h))
		return -ENOTSUP;
	d->img.create(h, w, CV_8UC1);
	int ret = mvod_png_grey_decode(d->png, buf, len, d->img.data, d->img.step[0]);
	if (ret)
		return ret;
	d->alloc.kept = d->img;
	d->flags = cv::IMREAD_GRAYSCALE | cv::IMREAD_IGNORE_ORIENTATION;
	return 0;
}

extern "C" int mvod_imgdec_decode(struct mvod_imgdec *d, const void *buf, size_t len,
				  struct mvod_image *img)
{
	if (len == 0 || len > INT_MAX)
		return -EINVAL;
	return mvod_guarded([&] {
		if (!grey_png(d, (const uint8_t *)buf, len))
			return view_of(d->img, img);
		cv::Mat raw(1, (int)len, CV_8UC1, const_cast<void *>(buf));
		d->img.release();
		cv::imdecode(raw, d->flags, &d->img);
		if (d->img.empty())
			return -EINVAL;
		d->alloc.kept = d->img;
		d->flags = (d->img.channels() == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR) |
			   cv::IMREAD_IGNORE_ORIENTATION;
		return view_of(d->img, img);
	});
}

extern "C" void mvod_imgdec_destroy(struct mvod_imgdec *d)
{
	delete d;
}
