/*
 * The frames the VO holds: the reference frame and the current one, each a slot of the same
 * shape (its features, the structure seen from it, its pose, the map points its keypoints
 * track), and the current frame's matches against the reference: the one record the front end
 * fills and the modes read. Promoting the current frame to the reference swaps the slots
 * whole, so nothing of a frame is left behind or copied. Everything is allocated at init.
 */
#ifndef MVOD_VO_CORE_FRAME_H
#define MVOD_VO_CORE_FRAME_H

#include <stdbool.h>
#include <stdint.h>

#include "id.h"
#include "mvod/geom.h"
#include "types.h"

struct mvod_vo_frame {
	struct mvod_features f;
	double *pts; /* cap * 3: point in this camera's frame, absolute units */
	uint8_t *has_pt;
	/*
	 * When a two-view step made this frame (has_par; else par is stale): per keypoint, the
	 * parallax that step measured there, pixels with the rotation removed, 0 for a point that
	 * was not an inlier in front. An inlier's point is in pts even when has_pt is 0 (too far
	 * for structure scale): two-view's depth scale takes those with parallax.
	 */
	int has_par;
	float *par; /* cap */
	struct mvod_pose pose; /* camera-to-world */
	double gt[3]; /* ground-truth position, with --scale gt */
	double odo;   /* --scale external: odometer at this frame, metres; NAN unknown */
	int64_t seq;  /* the frame's number among those processed */
	/* Map mode: the map point each keypoint observes, or MVOD_MAP_NONE. [cap] */
	mvod_map_id *pt;
	/*
	 * Map mode with KLT: where each track was first seen on a keyframe (keyframe id and
	 * keypoint), or kf MVOD_MAP_NONE: a track with no point yet is triangulated from there,
	 * the widest baseline it has. [cap]
	 */
	struct mvod_map_obs *first;
};

struct mvod_frames {
	struct mvod_vo_frame slot[2]; /* storage behind ref and cur */
	struct mvod_vo_frame *ref, *cur;
	bool have_ref;
	int64_t count; /* frames begun: the next one's seq */
	int cap;       /* keypoints a frame holds */
	/*
	 * The current frame's matches against the reference: {reference index, current index},
	 * n_matches of them. The KLT front end writes them while tracking; with descriptors, the
	 * matcher when a mode matches the two (frontend/fe.h). [cap]
	 */
	struct mvod_match *matches;
	int n_matches;
};

/* For frames of up to cap keypoints with descriptors of desc_bytes. 0 or -ENOMEM. */
int mvod_frames_init(struct mvod_frames *fr, int cap, int desc_bytes);
/* Frees what init allocated; an fr zeroed or failed at init is fine. */
void mvod_frames_fini(struct mvod_frames *fr);
/* A new current frame: its seq, no parallax yet, no matches. */
void mvod_frames_begin(struct mvod_frames *fr);
/*
 * The current frame becomes the reference, at camera-to-world pose and with ground-truth
 * position gt (NULL: none). Its structure (from a motion step) is what the next step scales
 * against; without (with_structure false) the next step falls back to constant speed.
 */
void mvod_frames_promote(struct mvod_frames *fr, const struct mvod_pose *pose, const double *gt,
			 bool with_structure);
/*
 * The reference's position scaled by f about the world's origin: the first metric measurement
 * rescales the chain so far, which was in the unit the measurement corrects.
 */
void mvod_frames_scale_ref(struct mvod_frames *fr, double f);
/* The ground-truth length of the step from the reference to the current frame at gt. */
double mvod_frames_gt_step(const struct mvod_frames *fr, const double gt[3]);

#endif
