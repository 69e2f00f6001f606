/* What the capture backends share: their registration and path helpers (errors: util/errbuf.h). */
#ifndef MVOD_CAPTURE_BACKENDS_H
#define MVOD_CAPTURE_BACKENDS_H

#include <stddef.h>

#include "mvod/capture.h"
#include "util/errbuf.h"

extern const struct mvod_source_ops mvod_source_file_ops;
extern const struct mvod_source_ops mvod_source_images_ops;
extern const struct mvod_source_ops mvod_source_kitti_ops;
extern const struct mvod_source_ops mvod_source_kitti_raw_ops;
extern const struct mvod_source_ops mvod_source_euroc_ops;
extern const struct mvod_source_ops mvod_source_tum_ops;
extern const struct mvod_source_ops mvod_source_v4l2_ops;
extern const struct mvod_source_ops mvod_source_libcamera_ops;

/* "dir/name" into buf; -ENAMETOOLONG with the reason in err when it does not fit. */
int mvod_capture_path(char *buf, size_t len, const char *dir, const char *name, char *err,
		      size_t errlen);

#endif
