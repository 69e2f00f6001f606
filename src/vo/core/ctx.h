/*
 * What the facade (vo.c) hands the two modes (twoview/, map/): the configuration, the camera
 * and the state they share, each with one owner (the frames: frame.h; the scale: scale.h;
 * the front end: frontend/fe.h), and what a mode answers for a frame, which only the
 * facade applies. The facade owns all of it; a mode keeps the context from its create.
 */
#ifndef MVOD_VO_CORE_CTX_H
#define MVOD_VO_CORE_CTX_H

#include <stdbool.h>

#include "frame.h"
#include "mvod/calib.h"
#include "mvod/vo_types.h"
#include "scale.h"

struct mvod_fe;

struct mvod_vo_ctx {
	const struct mvod_vo_params *p; /* resolved: the front end and the mode that run */
	const struct mvod_camera *cam;  /* of the preprocessed frames: pinhole, no distortion */
	struct mvod_frames *fr;
	struct mvod_scale *scale;
	struct mvod_fe *fe;
	bool klt; /* the front end tracks KLT corners (no descriptors) */
	int cap;  /* keypoints a frame holds */
};

/*
 * A mode's answer for one frame, besides what it reports in mvod_vo_result (status, counts).
 * The frame's state and whether it becomes the reference follow from its status (vo.c,
 * settle), the same for both modes.
 */
struct mvod_step {
	struct mvod_pose pose; /* camera-to-world to publish; in: the last published */
	/*
	 * Two-view: the step's median flow, pixels, left after the rotation-only fit: the pair's
	 * parallax whatever the essential matrix says (map mode's first map checks it); HUGE_VAL
	 * when no rotation fits.
	 */
	double free_parallax_px;
};

#endif
