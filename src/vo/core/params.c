/*
 * The VO's public types' names, defaults and predicates (mvod/vo_types.h): what the option
 * table, the run loop and mvod bench ask of a configuration, apart from the VO object.
 */
#include "mvod/vo_types.h"

#include <stddef.h>

const char *const mvod_stage_names[MVOD_STAGE_COUNT] = {"capture", "preprocess", "detect", "match",
							 "pose"};

const char *mvod_frame_status_name(enum mvod_frame_status s)
{
	static const char *const names[] = {"motion",      "first",        "rotation",
					    "few-features", "few-matches", "ransac-failed",
					    "few-inliers"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

const char *mvod_scale_source_name(enum mvod_scale_source s)
{
	static const char *const names[] = {"none", "structure", "constant-speed", "ground-truth",
					    "unit", "map", "height", "external"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

const char *const mvod_frontend_names[] = {"orb", "klt", "auto", NULL};
const char *const mvod_detector_names[] = {"orb", "sift", NULL};
const char *const mvod_matcher_names[MVOD_MATCHER_COUNT + 1] = {"bf", "bf-cross", "bf-ratio",
								"flann", "flann-ratio", NULL};
const char *const mvod_robust_names[] = {"magsac", "ransac", NULL};
const char *const mvod_vo_mode_names[] = {"twoview", "map", NULL};
#define DETECTORS ((int)(sizeof(mvod_detector_names) / sizeof(mvod_detector_names[0])) - 1)

const char *mvod_detector_name(enum mvod_detector d)
{
	return (unsigned)d < DETECTORS ? mvod_detector_names[d] : "unknown";
}

const char *mvod_matcher_kind_name(enum mvod_matcher_kind m)
{
	return (unsigned)m < MVOD_MATCHER_COUNT ? mvod_matcher_names[m] : "unknown";
}

bool mvod_matcher_uses_ratio(enum mvod_matcher_kind k)
{
	return k == MVOD_MATCHER_BF || k == MVOD_MATCHER_BF_RATIO || k == MVOD_MATCHER_FLANN_RATIO;
}

/*
 * Map mode is the default (issue 12): on KLT tracks it beats two-view on the KITTI clips with
 * --scale gt, free scale and the camera's height, and on mvod-synth's KITTI 00 drive with the
 * camera's height (BENCHMARKS.md, "KITTI clips" and "Long drives"). It runs with every
 * --scale and needs no Ceres.
 */
void mvod_vo_params_default(struct mvod_vo_params *p)
{
	*p = (struct mvod_vo_params){
		.mode = MVOD_VO_MAP,
		.resize = 1.0,
		.blur_ksize = 0,
		.frontend = MVOD_FRONTEND_AUTO,
		.detector = MVOD_DETECTOR_ORB,
		.max_features = 2000,
		.max_tracks = 500,
		.matcher = MVOD_MATCHER_BF,
		.ratio = 0.8,
		.best_n = 200,
		.robust = MVOD_ROBUST_MAGSAC,
		.ransac_px = 1.0,
		.ransac_conf = 0.999,
		.min_matches = 30,
		.min_inliers = 20,
		.min_parallax_px = 1.0,
		.scale_mode = MVOD_SCALE_MODE_AUTO,
	};
}

const char *const mvod_vo_descriptor_flags[] = {"detector", "matcher", "ratio", "best", NULL};

const char *mvod_vo_descriptor_option(const struct mvod_vo_params *p)
{
	struct mvod_vo_params d;
	mvod_vo_params_default(&d);
	/* In the order of mvod_vo_descriptor_flags. */
	bool differs[] = {p->detector != d.detector, p->matcher != d.matcher, p->ratio != d.ratio,
			  p->best_n != d.best_n};
	for (int i = 0; mvod_vo_descriptor_flags[i]; i++)
		if (differs[i])
			return mvod_vo_descriptor_flags[i];
	return NULL;
}

/*
 * The one place auto is decided: klt in both modes (map mode on KLT tracks beat it on ORB
 * descriptors in every figure on KITTI 06/07: free-scale drift 1.007/1.035 against
 * 1.066/1.384; BENCHMARKS.md), orb when the user sets an option only the descriptor front end
 * has. Not --features, which both descriptor detectors read: `[vo] features = 1500` made auto
 * run orb, 8x slower (38 against 316-322 fps), where the user meant fewer or more of anything.
 */
enum mvod_frontend mvod_vo_frontend(const struct mvod_vo_params *p)
{
	if (p->frontend != MVOD_FRONTEND_AUTO)
		return p->frontend;
	if (mvod_vo_descriptor_option(p))
		return MVOD_FRONTEND_ORB;
	return MVOD_FRONTEND_KLT;
}

const char *mvod_vo_frontend_name(const struct mvod_vo_params *p)
{
	if (mvod_vo_frontend(p) == MVOD_FRONTEND_KLT)
		return mvod_frontend_names[MVOD_FRONTEND_KLT];
	return mvod_detector_name(p->detector);
}

bool mvod_vo_tracked(const struct mvod_vo_result *res)
{
	return res->state == MVOD_STATE_TRACKING &&
	       (res->status == MVOD_FRAME_MOTION || res->status == MVOD_FRAME_ROTATION);
}

double mvod_vo_quality(const struct mvod_vo_params *p, const struct mvod_vo_result *res)
{
	if (!mvod_vo_tracked(res))
		return 0;
	double q = res->inliers / (double)(MVOD_QUALITY_INLIERS * p->min_inliers);
	return q < 1 ? q : 1;
}

bool mvod_scale_mode_metric(enum mvod_scale_mode m)
{
	return m == MVOD_SCALE_MODE_GT || m == MVOD_SCALE_MODE_HEIGHT ||
	       m == MVOD_SCALE_MODE_EXTERNAL;
}
