/*
 * Video files decoded by FFmpeg's libavformat and libavcodec directly, handed out as 8-bit grey:
 * the luma plane of grey and YUV video as the decoder wrote it (no copy), anything else (RGB,
 * packed YUV, more than 8 bits) converted to grey once by libswscale. OpenCV's reader, used
 * before, always converted to BGR (which mvod turned back into grey) and kept the size it opened
 * with after a resolution change; this one hands each frame at its own size, so the caller can
 * tell such frames apart. Steady state does not allocate in mvod's code (FFmpeg reuses its
 * frame pool); a frame stays valid until the next read or the close.
 */
#ifndef MVOD_CAPTURE_VIDEO_H
#define MVOD_CAPTURE_VIDEO_H

#include <stdint.h>

#include "mvod/capture.h"
#include "mvod/image.h"

struct mvod_video;

/*
 * Opens the file and decodes its first frame (kept for the first read): -EINVAL when FFmpeg
 * cannot open the file, finds no video stream or no decoder for it, -E2BIG when the stream's
 * size is past MVOD_FRAME_MAX_PIXELS (capture/image_header.h), -ENODATA when it holds no
 * frame (a video of none once "succeeded" with 0 frames). No frame is decoded beyond the
 * stream's pixel count (FFmpeg's max_pixels): a frame that states more is not allocated.
 */
int mvod_video_open(const char *path, struct mvod_video **out);
/*
 * Size, nominal fps (0 = unknown) and frame count (-1 = unknown) the container declares; for
 * a container without a count (Matroska), its duration times the rate, as OpenCV estimated it.
 */
void mvod_video_props(struct mvod_video *v, struct mvod_source_info *info);
/*
 * The next frame in presentation order, grey, at the size it was coded at, and its media time
 * in microseconds from the stream's start (0 when the container gives none). Packets the
 * decoder refuses (corrupt) are skipped. -EMSGSIZE for a frame not of the size props gave (a
 * resolution change mid-stream): img has its size and no pixels, media_us its time. -ENODATA
 * when the decoder delivers no further frame, whether the stream ended or broke off: only the
 * caller, knowing the frame count, can tell.
 */
int mvod_video_read(struct mvod_video *v, struct mvod_image *img, int64_t *media_us);
/* NULL is a no-op. */
void mvod_video_close(struct mvod_video *v);

#endif
