/*
 * The OpenCV door of the capture backends: video decoding (cv::VideoCapture over FFmpeg) and
 * still-image decoding (cv::imdecode). Plain C. Every function catches every exception and
 * returns 0 or -errno. Frames are views of a buffer the object keeps and reuses, so steady
 * state does not allocate; a view stays valid until the next read/decode or the destroy.
 */
#ifndef MVOD_VIDEO_SHIM_H
#define MVOD_VIDEO_SHIM_H

#include <stddef.h>
#include <stdint.h>

#include "mvod/capture.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_video;
/* -EINVAL when FFmpeg cannot open or decode the file (not a video, corrupt header). */
int mvod_video_open(const char *path, struct mvod_video **out);
/* Size, nominal fps (0 = unknown) and frame count (-1 = unknown) the container declares. */
void mvod_video_props(struct mvod_video *v, struct mvod_source_info *info);
/*
 * The next frame as 8-bit grey or BGR and its media time in microseconds (0 when the
 * container gives none). -ENODATA when the decoder delivers no further frame, whether the
 * stream ended or broke: only the caller, knowing the frame count, can tell which.
 */
int mvod_video_read(struct mvod_video *v, struct mvod_image *img, int64_t *media_us);
/* NULL is a no-op. */
void mvod_video_close(struct mvod_video *v);

/*
 * Still images (PNG, JPEG, PNM, BMP, TIFF) from an encoded buffer. The first image decides
 * the pixel format (grey stays grey, anything with colour is BGR); later images are
 * converted to it. 16-bit samples keep their high byte, alpha is dropped.
 */
struct mvod_imgdec;
int mvod_imgdec_create(struct mvod_imgdec **out);
/* -EINVAL when buf is not an image OpenCV can decode. */
int mvod_imgdec_decode(struct mvod_imgdec *d, const void *buf, size_t len, struct mvod_image *img);
/* NULL is a no-op. */
void mvod_imgdec_destroy(struct mvod_imgdec *d);

#ifdef __cplusplus
}
#endif

#endif
