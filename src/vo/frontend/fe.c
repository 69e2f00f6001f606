#include "fe.h"

#include <errno.h>
#include <stdlib.h>

#include "cv_shim.h"
#include "klt.h"
#include "match.h"

/*
 * A share of the features on the road band (core/camera.h): with KLT and --scale height, a
 * share of the tracks, whose smooth asphalt the tracker's own detection leaves almost bare
 * (KITTI 06: one step in 50 found 20 ground points). With ORB, every scale mode, detected on
 * the band with FAST's contrast lowered. --scale height needs it: ORB's own 2000 features
 * found no ground on KITTI 06, whose steps then stayed held for want of a first scale (the
 * whole clip at the origin). The others too: ORB's strongest corners cluster on buildings and
 * cars, mostly far, whose flow hardly depends on the translation; the road's near points,
 * with the largest parallax, pin its direction (with twoview's refinement, KITTI 07's
 * direction error per frame 3.22 -> 1.19 deg; BENCHMARKS.md, issue 12's "ORB's two-view pose
 * refined").
 */
#define BAND_SHARE 3     /* a third of max_tracks or max_features (see BENCHMARKS.md, issue 14) */
#define BAND_FAST 10     /* FAST contrast on the band, grey levels */

struct mvod_fe {
	struct mvod_cv_detector *det; /* descriptors: the detector and matcher */
	struct mvod_matcher *matcher;
	struct mvod_klt *klt;         /* or KLT */
	int max_features, max_tracks;
	bool reserve_band;            /* KLT with --scale height: tracks kept on the band */
	int desc_bytes;
};

static int descriptors_create(struct mvod_fe *fe, const struct mvod_vo_params *p,
			      const struct mvod_camera *cam, int cap)
{
	int ret = mvod_cv_detector_create(p->detector, p->max_features, cam->width, cam->height,
					  &fe->det);
	if (ret)
		return ret;
	struct mvod_match_params mp = {p->matcher, p->detector, p->ratio, p->best_n};
	return mvod_matcher_create(&mp, cap, &fe->matcher);
}

static int klt_create(struct mvod_fe *fe, const struct mvod_vo_params *p,
		      const struct mvod_camera *cam)
{
	struct mvod_klt_params kp;
	mvod_klt_params_default(&kp);
	kp.max_tracks = p->max_tracks;
	return mvod_klt_create(&kp, cam->width, cam->height, &fe->klt);
}

int mvod_fe_create(const struct mvod_vo_params *p, const struct mvod_camera *cam, int cap,
			 struct mvod_fe **out)
{
	*out = NULL;
	struct mvod_fe *fe = calloc(1, sizeof(*fe));
	if (!fe)
		return -ENOMEM;
	fe->max_features = p->max_features;
	fe->max_tracks = p->max_tracks;
	fe->reserve_band = p->scale_mode == MVOD_SCALE_MODE_HEIGHT;
	fe->desc_bytes = mvod_cv_desc_bytes(p->detector);
	bool klt = p->frontend == MVOD_FRONTEND_KLT;
	int ret = klt ? klt_create(fe, p, cam) : descriptors_create(fe, p, cam, cap);
	if (ret) {
		mvod_fe_destroy(fe);
		return ret;
	}
	*out = fe;
	return 0;
}

void mvod_fe_destroy(struct mvod_fe *fe)
{
	if (!fe)
		return;
	mvod_cv_detector_destroy(fe->det);
	mvod_matcher_destroy(fe->matcher);
	mvod_klt_destroy(fe->klt);
	free(fe);
}

int mvod_fe_desc_bytes(const struct mvod_fe *fe)
{
	return fe->desc_bytes;
}

static int klt_track(struct mvod_fe *fe, const struct mvod_image *grey, const float *band,
		     struct mvod_frames *fr)
{
	int ret = mvod_klt_track(fe->klt, grey, &fr->cur->f, fr->matches, &fr->n_matches);
	if (ret || !fe->reserve_band || !band)
		return ret;
	return mvod_klt_reserve(fe->klt, grey, band, fe->max_tracks / BAND_SHARE, BAND_FAST,
				&fr->cur->f);
}

int mvod_fe_run(struct mvod_fe *fe, const struct mvod_image *grey, const float *band,
		      struct mvod_frames *fr)
{
	if (fe->klt)
		return klt_track(fe, grey, band, fr);
	if (!band)
		return mvod_cv_detect(fe->det, grey, &fr->cur->f);
	return mvod_cv_detect_band(fe->det, grey, band, fe->max_features / BAND_SHARE, BAND_FAST,
				   &fr->cur->f);
}

int mvod_fe_match_ref(struct mvod_fe *fe, struct mvod_frames *fr)
{
	if (fe->klt) /* matched while tracking */
		return 0;
	return mvod_match(fe->matcher, &fr->ref->f, &fr->cur->f, fr->matches, fr->cap,
			  &fr->n_matches);
}

int mvod_fe_match(struct mvod_fe *fe, const struct mvod_features *a,
			const struct mvod_features *b, struct mvod_match *out, int cap, int *n)
{
	if (!fe->matcher)
		return -EINVAL;
	return mvod_match(fe->matcher, a, b, out, cap, n);
}

void mvod_fe_promote(struct mvod_fe *fe)
{
	if (fe->klt)
		mvod_klt_promote(fe->klt);
}

void mvod_fe_reset(struct mvod_fe *fe)
{
	mvod_klt_reset(fe->klt);
}
