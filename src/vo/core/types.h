/*
 * The VO's own types: keypoints, feature sets and matches. Plain C, shared by the detector door
 * (cv_shim), the matcher and the two-view estimator; nothing outside src/vo/ uses them.
 */
#ifndef MVOD_VO_CORE_TYPES_H
#define MVOD_VO_CORE_TYPES_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MVOD_ORB_DESC_BYTES 32
#define MVOD_SIFT_DESC_BYTES (128 * 4) /* 128 floats */

struct mvod_keypoint {
	float x, y;     /* pixels in the preprocessed image */
	int octave;     /* pyramid level the detector found it on (OpenCV's KeyPoint::octave) */
	float response; /* detector score, larger is stronger (for choosing among keypoints) */
};

/* Caller-owned: kp[cap], desc[cap * desc_bytes]. */
struct mvod_features {
	int n, cap;
	int desc_bytes; /* MVOD_ORB_DESC_BYTES (binary) or MVOD_SIFT_DESC_BYTES (float) */
	struct mvod_keypoint *kp;
	uint8_t *desc;
};

struct mvod_match {
	int a, b;   /* index into the first and second feature set */
	float dist; /* descriptor distance: Hamming bits (ORB) or L2 (SIFT) */
};

#ifdef __cplusplus
}
#endif

#endif
