/* Plain image views shared by every stage. */
#ifndef MVOD_IMAGE_H
#define MVOD_IMAGE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum mvod_pixfmt {
	MVOD_PIX_GREY = 0, /* 8-bit, 1 channel */
	MVOD_PIX_BGR = 1,  /* 8-bit, 3 channels, OpenCV order */
};

/* A view: data is borrowed from whoever produced it, never freed through the view. */
struct mvod_image {
	int w, h;
	int stride; /* bytes per row */
	enum mvod_pixfmt fmt;
	uint8_t *data;
};

#ifdef __cplusplus
}
#endif

#endif
