/*
 * Matching by projection (ORB-SLAM's SearchByProjection): each map point is projected with the
 * predicted pose and paired with the nearest keypoint by descriptor among those within a
 * radius of its projection. The current frame's keypoints are bucketed into a grid of cells
 * once per frame, so a point looks at a few cells, not at every keypoint. Plain C, fixed
 * arrays sized at create; nothing is allocated per frame.
 */
#ifndef MVOD_PROJECT_MATCH_H
#define MVOD_PROJECT_MATCH_H

#include <stdint.h>

#include "map.h"

#define MVOD_PM_UNMATCHED (-1)   /* in view, no keypoint passed */
#define MVOD_PM_OUT_OF_VIEW (-2) /* behind the camera or off the image */

struct mvod_pm_params {
	/*
	 * Search radius in pixels for a keypoint of octave 0; a keypoint of octave o is accepted
	 * within radius_px * scale_factor^o (it is located that much less precisely). ORB-SLAM
	 * uses 1 x the level scale (3 after relocalisation); tracking with a constant-velocity
	 * prediction needs more: the prediction is off by the change of speed.
	 */
	double radius_px;
	double scale_factor; /* the detector's pyramid step: 1.2 for ORB */
	int max_octave;      /* highest octave of the detector (7 for 8 levels) */
	int max_dist;        /* Hamming bits: ORB-SLAM's TH_HIGH = 100 of 256 */
	double ratio;        /* best < ratio * second best, else ambiguous: 0.8 as ORB-SLAM */
	int cell_px;         /* grid cell side, pixels */
};

void mvod_pm_params_default(struct mvod_pm_params *p);

struct mvod_pm;
/* For images of width x height pixels with up to kp_cap keypoints. */
int mvod_pm_create(const struct mvod_pm_params *p, int width, int height, int kp_cap,
		   struct mvod_pm **out);
void mvod_pm_destroy(struct mvod_pm *pm);

/*
 * The current frame: n keypoints kp[n] and their ORB descriptors desc[n * 32], borrowed (not
 * copied) until the next call. Builds the grid. -EINVAL for n > kp_cap or an octave outside
 * [0, max_octave].
 */
int mvod_pm_set_frame(struct mvod_pm *pm, const struct mvod_map_kp *kp, const uint8_t *desc,
		      int n);

/*
 * Projects n points (pos[n * 3], world) with the camera-from-world pose Rcw, tcw and
 * K = fx, fy, cx, cy, and matches them to the frame's keypoints: match[i] = keypoint index,
 * MVOD_PM_UNMATCHED or MVOD_PM_OUT_OF_VIEW; dist[i] (may be NULL) its Hamming distance. A
 * keypoint goes to at most one point: the closest by descriptor (the loser is unmatched).
 * Returns the number of points matched.
 */
int mvod_pm_match(struct mvod_pm *pm, const double Rcw[9], const double tcw[3], const double K[4],
		  const double *pos, const uint8_t *desc, int n, int *match, int *dist);

#endif
