/* The capture backends' registration: the ops table of each scheme (source.c lists them). */
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


#endif
