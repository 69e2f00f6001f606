/*
 * The coded size of each frame of a video, read from its packets apart from the decoder.
 * OpenCV's FFmpeg reader keeps the size it opened with: after a resolution change mid-stream
 * it hands out frames of the old size holding stale or garbled pixels, and says nothing
 * (measured with OpenCV 4.6 and FFmpeg 5.1). FFmpeg's parsers read the size from each
 * sequence header (MPEG-1/2/4, H.264, HEVC, ...), so file: can tell such frames apart.
 */
#ifndef MVOD_CAPTURE_VIDEO_SIZE_H
#define MVOD_CAPTURE_VIDEO_SIZE_H

struct mvod_vsize;

/*
 * Follows path's first video stream. -ENOTSUP when its codec has no parser (intra-only
 * codecs such as FFV1 carry their size in the container only, where it cannot change).
 */
int mvod_vsize_open(const char *path, struct mvod_vsize **out);
/*
 * The coded size of the next frame, in decode order, which for a size change (at a key frame,
 * where reordering starts over) is also the order frames come out: 0 with w and h (0 when
 * the stream has not said yet), -ENODATA at the end, -EIO on a read error.
 */
int mvod_vsize_next(struct mvod_vsize *v, int *w, int *h);
/* NULL is a no-op. */
void mvod_vsize_close(struct mvod_vsize *v);

#endif
