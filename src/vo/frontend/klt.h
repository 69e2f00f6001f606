/*
 * The KLT front end: corners found by FAST, ranked by their Harris score and spread over a grid
 * of cells, then followed frame to frame by pyramidal Lucas-Kanade with a motion-predicted
 * initial flow and a forward-backward check. Each frame yields its tracked points as a feature
 * set and, for the tracks the reference frame holds, matches against it: what the two-view
 * estimator takes from the descriptor front end, without descriptors.
 */
#ifndef MVOD_KLT_H
#define MVOD_KLT_H

#include "mvod/image.h"
#include "vo/core/types.h"

struct mvod_klt_params {
	int max_tracks;  /* tracks kept at most; corners are detected when fewer than 3/4 remain */
	double fb_px;    /* forward-backward check: a track whose point, tracked forward then back,
			  * lands farther than this from where it started (pixels) is dropped */
	int fast_threshold; /* FAST's grey-level contrast at full size (halved per level: klt.c) */
};
/* max_tracks 500, fb_px 0.5, fast_threshold 20. */
void mvod_klt_params_default(struct mvod_klt_params *p);

struct mvod_klt;

/* For width x height grey frames; every buffer of the tracker is allocated here. */
int mvod_klt_create(const struct mvod_klt_params *p, int width, int height, struct mvod_klt **out);
void mvod_klt_destroy(struct mvod_klt *k);

/*
 * Tracks the points of the previous frame into grey (borrowed for the call), tops them up with
 * new corners when they run low, and writes them to f (f->kp; f->desc is left alone; f->cap must
 * hold max_tracks) in track order. matches[f->cap] receives, for each track the reference
 * frame holds, {reference index, index in f, forward-backward error in pixels}; *n_matches
 * their count.
 */
int mvod_klt_track(struct mvod_klt *k, const struct mvod_image *grey, struct mvod_features *f,
		   struct mvod_match *matches, int *n_matches);

/*
 * Reserves tracks for a region of the frame just tracked (--scale height: the road band, whose
 * smooth asphalt FAST at fast_threshold rarely ranks among the strongest corners): when fewer
 * than share live tracks lie inside the convex quadrilateral quad (4 corners (x, y) in order,
 * pixels), FAST corners of grey at band_threshold inside it become new tracks, in the place of
 * the youngest tracks outside it that the reference does not hold, or in free capacity. f and
 * the matches mvod_klt_track wrote stay valid: replaced tracks had no match, f is updated.
 * Returns 0 or -errno.
 */
int mvod_klt_reserve(struct mvod_klt *k, const struct mvod_image *grey, const float quad[8],
		     int share, int band_threshold, struct mvod_features *f);

/* The frame last tracked became the reference: its feature i is track i. */
void mvod_klt_promote(struct mvod_klt *k);

/* Forgets every track and the previous frame (a gap in the frames); NULL: a no-op, as mvod_mapvo_reset. */
void mvod_klt_reset(struct mvod_klt *k);

#endif
