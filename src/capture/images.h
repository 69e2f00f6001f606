/*
 * A directory of image files as a frame source, with timestamps from a times.txt. The
 * images: backend is this with DIR/times.txt; kitti: reuses it for SEQDIR/image_0.
 */
#ifndef MVOD_CAPTURE_IMAGES_H
#define MVOD_CAPTURE_IMAGES_H

#include <stddef.h>
#include <stdint.h>

#include "capture/backends.h"
#include "capture/video_shim.h"

struct mvod_images {
	char **paths;             /* sorted "dir/name"; one allocation holds pointers and strings */
	size_t n;                 /* number of images, at least 1 once open */
	size_t next;              /* index of the next read */
	int64_t *times_us;        /* n times from times.txt, or NULL for the 10 Hz default */
	uint8_t *buf;             /* file contents, grown only for a file larger than any before */
	size_t cap;               /* bytes allocated in buf, never above limit */
	size_t limit;             /* largest frame file read, bytes (see images.c) */
	struct mvod_imgdec *dec;  /* decodes into one reused pixel buffer */
	struct mvod_source_info info; /* size of the first image, count, rate of the times */
};

/*
 * Lists the images in dir (decoding the first for the frame size) and reads times_path. A
 * missing times_path is no error: timestamps then assume 10 Hz (info.times_assumed). im must be
 * zeroed; on failure it is left released and err says why.
 */
int mvod_images_open(struct mvod_images *im, const char *dir, const char *times_path, char *err,
		     size_t errlen);
/*
 * The same on a list another index made (a dataset's data.csv, rgb.txt): im takes paths (one
 * allocation, as in struct mvod_images) and times_us (n entries, malloc'ed) in any case. im
 * must be zeroed; on failure it is left released and err says why.
 */
int mvod_images_open_list(struct mvod_images *im, char **paths, size_t n, int64_t *times_us,
			  char *err, size_t errlen);
/*
 * The ops on an open struct mvod_images (priv), shared by every backend built on it. read
 * gives -EINVAL for an image it cannot read or decode, and the next read goes on after it.
 */
int mvod_images_read(void *priv, struct mvod_frame *frame, const struct mvod_image *into);
void mvod_images_info(void *priv, struct mvod_source_info *info);
void mvod_images_close(void *priv);

#endif
