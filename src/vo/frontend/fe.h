/*
 * The VO's front end: the current frame's features and their matches against the reference
 * frame, into the frame record (core/frame.h). Two kinds: KLT (FAST corners followed by
 * Lucas-Kanade: klt.h), matched as they are tracked and without descriptors; or descriptors
 * (ORB or SIFT detected in every frame: cv_shim.h) matched by match.h's matcher. Both keep a
 * share of their features on the road band (core/camera.h) when it is in view.
 */
#ifndef MVOD_VO_FRONTEND_FE_H
#define MVOD_VO_FRONTEND_FE_H

#include "mvod/calib.h"
#include "mvod/image.h"
#include "mvod/vo_types.h"
#include "vo/core/frame.h"

struct mvod_fe;

/*
 * The front end p->frontend names (resolved: KLT or ORB, which p->detector then picks) for
 * frames of cam's size (preprocessed), matching sets of up to cap features. Every buffer is
 * allocated here.
 */
int mvod_fe_create(const struct mvod_vo_params *p, const struct mvod_camera *cam, int cap,
			 struct mvod_fe **out);
void mvod_fe_destroy(struct mvod_fe *fe);

/* Bytes of one descriptor of this front end's features (KLT: ORB's size, unused). */
int mvod_fe_desc_bytes(const struct mvod_fe *fe);

/*
 * The current frame's features from grey (borrowed for the call) into fr->cur; KLT also
 * writes the tracks' matches against the reference into fr->matches. band: the road band's
 * quadrilateral in the image (core/camera.h), NULL when it is not in view.
 */
int mvod_fe_run(struct mvod_fe *fe, const struct mvod_image *grey, const float *band,
		      struct mvod_frames *fr);

/*
 * The current frame's matches against the reference in fr->matches and fr->n_matches: KLT's
 * from its tracking, else the descriptor matcher's.
 */
int mvod_fe_match_ref(struct mvod_fe *fe, struct mvod_frames *fr);

/*
 * The descriptor matcher on any two feature sets (map mode's keyframes): a against b into
 * out[cap], *n of them. -EINVAL with KLT, which has no descriptors.
 */
int mvod_fe_match(struct mvod_fe *fe, const struct mvod_features *a,
			const struct mvod_features *b, struct mvod_match *out, int cap, int *n);

/* KLT: the frame last tracked became the reference (its feature i is track i). */
void mvod_fe_promote(struct mvod_fe *fe);
/* Forgets every track (a gap in the frames). */
void mvod_fe_reset(struct mvod_fe *fe);

#endif
