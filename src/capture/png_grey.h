/*
 * 8-bit grey PNGs (KITTI's frames), decoded with libdeflate straight into a caller's buffer:
 * OpenCV's imdecode (libpng over zlib) cost 20.4e6 instructions per KITTI frame, zlib's
 * inflate 80 % of it (BENCHMARKS.md, "PNG decoding"). Any other PNG (colour, 16-bit, palette,
 * interlaced) and anything that is not a PNG is left to cv::imdecode (video_shim.cpp).
 */
#ifndef MVOD_PNG_GREY_H
#define MVOD_PNG_GREY_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_png;
/* The inflater and its scratch, which grows to the largest image seen and then stays. */
int mvod_png_create(struct mvod_png **out);
/* NULL is a no-op. */
void mvod_png_destroy(struct mvod_png *p);

/*
 * Size of the PNG in buf[len] when it is 8-bit grey and not interlaced; -ENOTSUP for any
 * other PNG or anything else.
 */
int mvod_png_grey_size(const uint8_t *buf, size_t len, int *w, int *h);

/*
 * Decodes it into dst (h rows of w bytes, stride bytes apart; the size mvod_png_grey_size
 * gave). -ENOTSUP as above, -EINVAL for a corrupt or truncated image (dst then undefined),
 * -ENOMEM. The chunks' CRCs are not checked: the zlib stream's Adler-32 covers the pixels.
 */
int mvod_png_grey_decode(struct mvod_png *p, const uint8_t *buf, size_t len, uint8_t *dst,
			 size_t stride);

#ifdef __cplusplus
}
#endif

#endif
