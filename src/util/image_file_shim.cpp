/* Image files, and PNG files that say their print resolution. */
#include "util/image_file.h"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <zlib.h>

#include "util/atomic_file.h"
#include "util/shim_guard.hpp"

namespace {

/* Signature (8 bytes) + IHDR (4 length + 4 type + 13 data + 4 CRC): pHYs must precede IDAT. */
const size_t AFTER_IHDR = 8 + 4 + 4 + 13 + 4;

void put_be32(std::vector<uchar> &v, uint32_t x)
{
	for (int s = 24; s >= 0; s -= 8)
		v.push_back((uchar)(x >> s));
}

/* pHYs: pixels per metre in x and y, unit 1 = metre. */
std::vector<uchar> phys_chunk(double dpi)
{
	uint32_t ppm = (uint32_t)std::lround(dpi / 0.0254);
	std::vector<uchar> c;
	put_be32(c, 9);
	const uchar type[] = {'p', 'H', 'Y', 's'};
	c.insert(c.end(), type, type + 4);
	put_be32(c, ppm);
	put_be32(c, ppm);
	c.push_back(1);
	uLong crc = crc32(0L, c.data() + 4, (uInt)(c.size() - 4));
	put_be32(c, (uint32_t)crc);
	return c;
}

} // namespace

extern "C" int mvod_image_file_write(const char *path, const char *ext,
				     const struct mvod_image *img, double dpi)
{
	if (!std::isfinite(dpi) || dpi < 0 || (dpi > 0 && std::strcmp(ext, ".png") != 0))
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat m(img->h, img->w, img->fmt == MVOD_PIX_BGR ? CV_8UC3 : CV_8UC1, img->data,
			  (size_t)img->stride);
		std::vector<uchar> buf;
		if (!cv::imencode(ext, m, buf))
			return -EIO;
		if (dpi > 0) {
			if (buf.size() < AFTER_IHDR)
				return -EIO;
			std::vector<uchar> phys = phys_chunk(dpi);
			buf.insert(buf.begin() + AFTER_IHDR, phys.begin(), phys.end());
		}
		return mvod_write_replace(path, buf.data(), buf.size());
	});
}
