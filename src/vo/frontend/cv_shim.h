/*
 * The OpenCV door of the VO. Plain C: image views in, caller-owned fixed-capacity arrays out.
 * Every function catches every exception and returns 0 or -errno (-EIO for an OpenCV error).
 */
#ifndef MVOD_CV_SHIM_H
#define MVOD_CV_SHIM_H

#include <stdbool.h>
#include <stdint.h>

#include "mvod/calib.h"
#include "mvod/image.h"
#include "mvod/vo_types.h"
#include "vo/core/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Undistort (maps computed once), resize, blur, grey: the whole preprocess stage. */
struct mvod_cv_preproc;
/*
 * cam: the source camera (width, height must be set). out_cam: the pinhole, distortion-free
 * camera of the output images. blur_ksize 0 = off, else odd.
 */
int mvod_cv_preproc_create(const struct mvod_camera *cam, double resize, int blur_ksize,
			   struct mvod_camera *out_cam, struct mvod_cv_preproc **out);
/* out views an internal buffer, valid until the next call. -EINVAL on a size/format mismatch. */
int mvod_cv_preproc_run(struct mvod_cv_preproc *p, const struct mvod_image *in,
			struct mvod_image *out);
void mvod_cv_preproc_destroy(struct mvod_cv_preproc *p);

/* Bytes of one descriptor of a detector. */
int mvod_cv_desc_bytes(enum mvod_detector kind);

struct mvod_cv_detector;
int mvod_cv_detector_create(enum mvod_detector kind, int max_features, int width, int height,
			    struct mvod_cv_detector **out);
/* Detects up to out->cap keypoints with descriptors (out->desc_bytes must match the detector). */
int mvod_cv_detect(struct mvod_cv_detector *d, const struct mvod_image *grey,
		   struct mvod_features *out);
/*
 * As mvod_cv_detect, but band_features of them (ORB) come from inside the image quadrilateral
 * quad (x, y four times, convex) with FAST's contrast threshold fast_threshold, and the rest
 * from outside it. SIFT detectors ignore the band (mvod_cv_detect).
 */
int mvod_cv_detect_band(struct mvod_cv_detector *d, const struct mvod_image *grey,
			const float quad[8], int band_features, int fast_threshold,
			struct mvod_features *out);
void mvod_cv_detector_destroy(struct mvod_cv_detector *d);

/*
 * Nearest neighbours by OpenCV: brute force L2 (float descriptors) or FLANN (LSH for binary,
 * kd-trees for float). OpenCV allocates its result vectors and, for FLANN, the index on every
 * call: this path is not allocation-free, unlike mvod's own Hamming table.
 */
struct mvod_cv_nn;
int mvod_cv_nn_create(enum mvod_detector kind, bool flann, struct mvod_cv_nn **out);
/*
 * For each feature i of a: the distances of its nearest and second nearest in b and the
 * nearest's index (-1 when none was found; second = best when only one was: such a match
 * cannot pass a ratio test). idx_b, when not NULL: for each feature of b, its nearest in a.
 */
int mvod_cv_nn_search(struct mvod_cv_nn *nn, const struct mvod_features *a,
		      const struct mvod_features *b, float *best_a, float *second_a, int *idx_a,
		      int *idx_b);
void mvod_cv_nn_destroy(struct mvod_cv_nn *nn);

#ifdef __cplusplus
}
#endif

#endif
