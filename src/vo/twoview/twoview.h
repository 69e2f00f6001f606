/*
 * The two-view algorithm: the motion between the reference frame and the current one from
 * their matches (a rotation-only model first, then the essential matrix, its decomposition by
 * cheirality, and the step length), as the pose to publish. Two-view mode runs it on every
 * frame; map mode where it has no map (before the first, and from a loss until the next).
 */
#ifndef MVOD_VO_TWOVIEW_TWOVIEW_H
#define MVOD_VO_TWOVIEW_TWOVIEW_H

#include <stdbool.h>

#include "vo/core/ctx.h"

struct mvod_twoview;

/* For the VO of context c (kept: it must outlive the object); buffers for c->cap matches. */
int mvod_twoview_create(const struct mvod_vo_ctx *c, struct mvod_twoview **out);
void mvod_twoview_destroy(struct mvod_twoview *tv);

/*
 * The motion of the current frame against the reference from the res->matches matches in
 * the frames' record: st->pose (the reference's pose moved by it) and st->free_parallax_px;
 * on MOTION also the current frame's structure (the next step's scale) and the speed (the
 * scale's); res's inliers, scale source and step. Returns the frame's status: MOTION,
 * ROTATION (translation held), RANSAC_FAILED or FEW_INLIERS. gt: this frame's ground-truth
 * position (--scale gt) or NULL.
 *
 * rebuild: map mode, from a loss until the new map. With --scale height or external its steps
 * take the lost map's last speed, exactly (map/init.c multiplies it by the frames a step
 * spans), neither the lost map's structure nor a height measurement; the new map's unit is
 * that step's. On mvod-synth's KITTI 00 drive KLT loses the map 104 times, every time with too
 * few tracks on map points (17-29 where tracking needs 30; the map holds 110-250), most in the
 * sharp turns of frames 3590-3840, where 80-110 of 500 tracks survive a frame; the lost
 * frame's few old points then scaled the steps that built the new maps at 0.9-1.5 times the
 * speed before (1.36 -> 2.07 of the truth at 3814), and no height fit corrected that unit
 * over the straight 4000-4340 (100-frame path ratios 1.19-1.42). Carried exactly: t_rel 4.88
 * -> 2.69 %, 100-frame windows 3600-4400 within 0.96-1.04 of the truth. A height measurement
 * on top (one two-view pair's road band): 3.64 %; the structure's step kept but clamped to
 * within 10 % of the speed: 4.54 %. --scale external the same, with the odometer's step on
 * top when there is speed (the step is the odometer's, as in two-view mode); without speed
 * the lost frame's points rebuilt KITTI 07's ORB map 1.93 times too large (speed stopping at
 * frame 80, map lost at 111): SE(3) ATE 6.45 m, at the last speed 0.54 m (06 KLT: 0.32 ->
 * 0.05 m).
 */
enum mvod_frame_status mvod_twoview_estimate(struct mvod_twoview *tv, const double *gt,
					     bool rebuild, struct mvod_vo_result *res,
					     struct mvod_step *st);

#endif
