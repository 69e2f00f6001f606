/* What vo.c (the state machine) and twoview.c (the two-view algorithm) share. */
#ifndef MVOD_VO_INTERNAL_H
#define MVOD_VO_INTERNAL_H

#include "vo/frontend/match.h"
#include "mvod/vo.h"
#include "vo/core/scale.h"
#include "vo/core/types.h"

/*
 * A frame slot: one frame's features and, for the reference frame, the structure seen from it.
 * Two slots hold the reference frame and the current one; promote() swaps them.
 */
struct frame_slot {
	struct mvod_features f;
	double *pts; /* cap * 3: point in this camera's frame, absolute units */
	uint8_t *has_pt;
	/*
	 * When a two-view step made this frame (has_par; else par is stale): per keypoint, the
	 * parallax that step measured there, pixels with the rotation removed, 0 for a point that
	 * was not an inlier in front. An inlier's point is in pts even when has_pt is 0 (too far
	 * for structure_scale): twoview.c's depth_scale takes those with parallax.
	 */
	int has_par;
	float *par; /* cap */
	struct mvod_pose pose; /* camera-to-world */
	double gt[3]; /* ground-truth position, with --scale gt */
	double odo;   /* --scale external: odometer at this frame, metres; NAN unknown */
	int64_t seq;  /* the frame's number among those processed (mvod_vo.frames) */
};

struct mvod_vo {
	struct mvod_vo_params p;
	struct mvod_camera cam; /* after preprocessing: pinhole, no distortion */
	struct mvod_cv_preproc *pre;
	struct mvod_cv_detector *det;
	struct mvod_matcher *matcher;
	struct mvod_klt *klt; /* the KLT front end (instead of det and matcher), or NULL */
	int klt_matches;      /* matches the KLT front end wrote into matches this frame */
	int cap;
	struct frame_slot slot[2]; /* storage behind ref and cur */
	struct frame_slot *ref, *cur;
	int have_ref;
	struct mvod_match *matches;
	double *x1, *x2, *depth, *prev_pts, *cur_pts, *scratch;
	uint8_t *mask;
	struct mvod_pose pose; /* last published pose */
	enum mvod_track_state state;
	int64_t frames;     /* frames processed, numbering the slots (seq) */
	/*
	 * The two-view step's median flow, pixels, left after the rotation-only fit: the pair's
	 * parallax whatever the essential matrix says; HUGE_VAL when no rotation fits.
	 */
	double free_parallax_px;
	double last_step;   /* the last translation step's length per frame it spanned: speed */
	int have_step;
	struct mvod_mapvo *mapvo; /* --mode map (mapvo.h), else NULL */
	struct mvod_scale_filter scale; /* --scale height, external */
};

/* --scale height: the road band (scale.h) in the image, along the expected ground normal. */
int mvod_vo_band_quad(const struct mvod_vo *vo, float quad[8]);

/*
 * The current frame becomes the reference. Its structure (from a motion step) is what the next
 * step scales against; without one, the next step falls back to constant speed.
 */
void mvod_vo_promote(struct mvod_vo *vo, const double *gt, bool with_structure);

/*
 * Motion of the current slot against the reference from res->matches matches in
 * vo->matches: updates vo->pose (and, on MOTION, the current slot's structure, the last step)
 * and res's inliers, scale source and step. Returns the frame status (MOTION, ROTATION,
 * RANSAC_FAILED, FEW_INLIERS). gt: this frame's ground-truth position (--scale gt) or NULL.
 */
enum mvod_frame_status mvod_twoview_estimate(struct mvod_vo *vo, const double *gt,
					     struct mvod_vo_result *res);

#endif
