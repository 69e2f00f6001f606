/*
 * An image file's size as its header states it, read before the pixels are decoded: a frame
 * file's header is checked against the sequence's size and a hard pixel cap, so a small file
 * that decompresses to gigabytes (an 875 KB PNG of 30000x30000 took RSS from 93 MB to 978 MB
 * before it was skipped for its size) is never decoded.
 */
#ifndef MVOD_CAPTURE_IMAGE_HEADER_H
#define MVOD_CAPTURE_IMAGE_HEADER_H

#include <stddef.h>
#include <stdint.h>

/*
 * Pixels a frame may have: 64 Mi (8192 x 8192). An 8K camera frame is 33 M; VO on more is
 * no use, and OpenCV's own decoder cap is 2^30.
 */
#define MVOD_FRAME_MAX_PIXELS ((int64_t)1 << 26)

/*
 * Width and height (pixels, 1 or more) from the header of a PNG, JPEG, PNM (P1-P6), BMP or
 * TIFF file held in buf[0, len). Returns 0, or -EINVAL when buf is none of those or its
 * header is cut short or states no size.
 */
int mvod_image_header_size(const uint8_t *buf, size_t len, int *w, int *h);

#endif
