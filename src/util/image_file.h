/* Image files written whole or not at all: the one encoder behind every PNG mvod writes. */
#ifndef MVOD_IMAGE_FILE_H
#define MVOD_IMAGE_FILE_H

#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Encodes img (grey or BGR) in the format ext names (".png", or any other OpenCV writes)
 * before any file exists, so an encoder error leaves nothing behind, then writes it to path
 * through temp+rename. dpi > 0 adds a PNG pHYs chunk saying the print resolution, so a board
 * printed at 100 % has its true size; it needs ext ".png". Returns 0 or -errno (-EINVAL for
 * a dpi that is negative, not finite or given for another format).
 */
int mvod_image_file_write(const char *path, const char *ext, const struct mvod_image *img,
			  double dpi);

#ifdef __cplusplus
}
#endif

#endif
