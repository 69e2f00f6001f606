/*
 * Map mode's metric scale: at a keyframe, with --scale height the camera's height over the
 * road band: with KLT over the band's tracks from the last frame triangulated with the map's
 * step (pair_ratio), with ORB among the window's map points (band_ratio); with --scale
 * external the odometer's distance over the map's own path since the last measurement
 * (odo_ratio, summed frame by frame: mvod_mapscale_frame); filtered as two-view mode's steps
 * are (scale.h), and, when the filtered estimate says the map's unit has drifted, the whole
 * map rescaled about the current camera. Bundle adjustment is landed first: a solve posted
 * before the rescale would bring back the old unit when it lands.
 */
#include "mapvo.h"

#include <math.h>
#include <string.h>

#include "vo/geom/motion.h"
#include "mvod/geom.h"

/*
 * The map is rescaled when the filtered metres per map unit is this far from 1 (log: 2 %): at
 * 20-40 band points a keyframe's height scatters by +-20 % on KITTI, so the filtered estimate
 * (gain 0.5) moves by a few per cent between keyframes with no real change; rescaling on that
 * would only shake the map BA is refining.
 */
#define MAP_RESCALE_MIN 0.02
/*
 * Bounded gain: once MVOD_MAPSCALE_WINDOW measurements are in, the rescales of the last
 * MVOD_MAPSCALE_WINDOW keyframes move the map's unit by at most this much together (log: 5 %,
 * 0.25 % a keyframe; with KLT a keyframe is a frame). In mvod-synth's KITTI 00 drive's sharp
 * turn (frames 3422-3435, 3.7 deg/frame) each keyframe's height read the map 10-14 % too
 * small, rescale after rescale: measured against the truth's steps the map's own unit held
 * within 4 % (metres per unit 1.47-1.53) while the band's measure of it went from 1.33 to
 * 2.77, and at gain 0.5 the map followed to 1.7 times the truth. Capped, that 100-frame
 * window ran 0.95 of the truth instead of 1.59, and frames 0-3400 at t_rel 2.29 % instead of
 * 2.97 % (the band's stretches of 10-20 % biased heights no longer move it fast either). The
 * first measurements go uncapped: from the first keyframe on, the unit converged too slowly
 * on the KITTI clips with ORB (few keyframes): 06 SE(3) ATE 0.750 -> 1.326 m, 07 scale drift
 * 1.395 -> 1.626. Windows of 10, 20, 40 and caps of 2-8 % replayed offline on KITTI 00's
 * measurements: 20 and 5 % (or 10 and 3.5 %) the best, a longer window much worse.
 */
#define MAP_RESCALE_CAP 0.05
/*
 * A band track's two rays, triangulated with the map's step, miss each other by less than
 * this (pixels at the point's depth): KLT's forward-backward check passes tracks within 0.5 px
 * (klt.c), so a static point's rays meet within about that; a car moving along the road
 * misses by its own motion's image.
 */
#define PAIR_GAP_PX 1.0
/*
 * Gain of the scale filter on a KLT keyframe's measurement (pair_ratio), instead of the
 * filter's 0.5: one frame's pair scatters by 11 % (log sd against the truth, KITTI 07; 3 % on
 * 06) where the map's points scattered by 2-4 %, and with KLT a keyframe is nearly a frame.
 * KITTI clips, map height SE(3) ATE mean over --tracks 480/500/520, 06 / 07: gain 0.5 0.475 /
 * 0.506 m, 0.35 0.434 / 0.487, 0.25 0.283 / 0.408, 0.15 0.271 / 0.399 (band_ratio at 0.5:
 * 0.609 / 0.385; two-view 0.322 / 0.599). mvod-synth's KITTI 00 height t_rel at 480/500/520:
 * 2.54 / 3.07 / 2.31 % at 0.25 (band_ratio: 2.24 % at 500); 2.31 % at 500 with gain 0.5;
 * with BA's function tolerance (mapping_ba.c) at 0.25: 2.76 / 2.52 / 2.05 %.
 */
#define PAIR_GAIN 0.25
/*
 * --scale external: the keyframe's ratio (the odometer's distance over the map's path since
 * the last measurement) is taken whole: it spans every frame since, so one frame's odometer
 * noise is averaged already. KITTI clips, exact speed / speed with 5 % noise a sample, map
 * klt SE(3) ATE 06 and 07: gain 0.25 0.057 / 0.120, 0.175 / 0.244 m; 0.5 0.051 / 0.104,
 * 0.121 / 0.248; 0.75 0.039 / 0.100, 0.114 / 0.266; 1 0.037 / 0.099, 0.087 / 0.267 (orb:
 * 1 the best in every column). A ratio more than EXT_GATE (log) from the map's unit is
 * refused, the gate doubling with each refusal in a row (scale.h): a wheel slipping, or a
 * stretch of bad odometry, moves the map by at most 25 % once. The map is rescaled when 0.5 %
 * off (2 %: 07 0.207 m; every keyframe: 0.084 m), with no bounded gain: the odometer has no
 * scene bias (height's turns) to guard against, and MAP_RESCALE_CAP cost 07 0.087 -> 0.165 m
 * (0.267 -> 0.330 m with noise).
 */
#define EXT_GAIN 1.0
#define EXT_GATE 0.22 /* log(1.25), as two-view's height gate */
#define EXT_RESCALE_MIN 0.005

/*
 * The map's points that lie on the road band as keyframe k sees it (projected into the band's
 * quadrilateral, in front of it), in its camera's frame, map units: metres per map unit. All
 * of the window's points, not only those k observes: on KITTI 06 (KLT front end, a keyframe
 * every frame) k observed 6-21 band points, too few for a ground of MVOD_GROUND_MIN_INLIERS on
 * 46 keyframes of 49, and the run stayed held until frame 27. At most vo->cap points (the
 * buffers' size), in the map's slot order.
 */
static double band_ratio(struct mvod_vo *vo, const struct mvod_map_keyframe *k, double *q)
{
	struct mvod_mapvo *mv = vo->mapvo;
	float quad[8];
	*q = 0;
	if (mvod_vo_band_quad(vo, quad) != 0)
		return NAN;
	int np = mvod_map_points(mv->map, mv->ids, mv->mp.point_cap), m = 0;
	for (int i = 0; i < np && m < vo->cap; i++) {
		double *X = vo->prev_pts + 3 * m, uv[2];
		mvod_rigid_apply(k->Rcw, k->tcw, mvod_map_point(mv->map, mv->ids[i])->pos, X);
		m += mvod_pinhole_pixel(mv->K, X, uv) &&
		     mvod_quad_contains(quad, (float)uv[0], (float)uv[1]);
	}
	return mvod_scale_height_ratio(&vo->scale, vo->prev_pts, m, vo->p.camera_height_m,
				       vo->scratch, q);
}

/*
 * KLT: the road band's tracks from the last frame, triangulated with the map's own step
 * between the two (mv->vR, mv->vt, map units), in this frame's camera; NAN when no ground
 * fits. It measures the unit of the map's motion, which is what the published path is made
 * of, where band_ratio measures the unit of its points, and the two disagree: against the
 * truth's step over |vt| at each keyframe, band_ratio read +3.5 % on KITTI 06 and -1.9 % on 07
 * (mean log, n = 19 / 39: the map's PnP steps longer, then shorter, than its points say),
 * this pair +1.7 % and +1.0 % (median -0.6 %; n = 27 / 61: it fits a ground more often than
 * the map's 10-60 band points do), two-view's own band +1.8 % and +0.2 %. 06's +1.7 % is
 * the clip's (its road under a 1.65 m camera), not the method's.
 */
static double pair_ratio(struct mvod_vo *vo, double *q)
{
	struct mvod_mapvo *mv = vo->mapvo;
	const struct mvod_camera *cam = &vo->cam;
	float quad[8];
	*q = 0;
	double len = sqrt(mv->vt[0] * mv->vt[0] + mv->vt[1] * mv->vt[1] + mv->vt[2] * mv->vt[2]);
	if (!(len > 0) || mvod_vo_band_quad(vo, quad) != 0)
		return NAN;
	int m = 0;
	for (int i = 0; i < vo->klt_matches && m < vo->cap; i++) {
		const struct mvod_keypoint *ka = &vo->ref->f.kp[vo->matches[i].a];
		const struct mvod_keypoint *kb = &vo->cur->f.kp[vo->matches[i].b];
		if (!mvod_quad_contains(quad, kb->x, kb->y))
			continue;
		double x1[3] = {(ka->x - cam->cx) / cam->fx, (ka->y - cam->cy) / cam->fy, 1};
		double x2[3] = {(kb->x - cam->cx) / cam->fx, (kb->y - cam->cy) / cam->fy, 1}, a[3];
		mvod_mat3_vec(mv->vR, x1, a);
		/* d1 a + vt = d2 x2 in least squares: the rays' closest points. */
		double aa = 0, ab = 0, bb = 0, at = 0, bt = 0;
		for (int k = 0; k < 3; k++) {
			aa += a[k] * a[k];
			ab += a[k] * x2[k];
			bb += x2[k] * x2[k];
			at += a[k] * mv->vt[k];
			bt += x2[k] * mv->vt[k];
		}
		double det = aa * bb - ab * ab;
		if (!(det > 1e-12))
			continue;
		double d1 = (ab * bt - at * bb) / det, d2 = (aa * bt - ab * at) / det;
		if (!(d1 > 0 && d2 > 0 && d2 <= MVOD_MOTION_SCALE_DEPTH * len))
			continue;
		double *X = vo->cur_pts + 3 * m, gap = 0;
		for (int k = 0; k < 3; k++) {
			double p1 = d1 * a[k] + mv->vt[k], p2 = d2 * x2[k];
			X[k] = 0.5 * (p1 + p2);
			gap += (p1 - p2) * (p1 - p2);
		}
		m += sqrt(gap) * cam->fx < PAIR_GAP_PX * d2;
	}
	return mvod_scale_height_ratio(&vo->scale, vo->cur_pts, m, vo->p.camera_height_m,
				       vo->scratch, q);
}

/* The map, the tracked frame, its velocity and the published pose scaled by s about c. */
static int rescale(struct mvod_vo *vo, const double c[3], double s)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int ret = mvod_map_rescale(mv->map, c, s);
	if (ret)
		return ret;
	mvod_map_scale_pose(mv->Rcw, mv->tcw, c, s);
	for (int k = 0; k < 3; k++) {
		mv->vt[k] *= s;
		vo->pose.t[k] = c[k] + s * (vo->pose.t[k] - c[k]);
	}
	mv->unit_log = 0;
	return 0;
}

enum mvod_scale_source mvod_mapscale_frame(struct mvod_vo *vo)
{
	struct mvod_mapvo *mv = vo->mapvo;
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT)
		return MVOD_SCALE_GROUND_TRUTH;
	if (vo->p.scale_mode != MVOD_SCALE_MODE_EXTERNAL)
		return MVOD_SCALE_MAP;
	if (!isfinite(vo->cur->odo)) {
		bool used;
		mvod_scale_filter_step(&vo->scale, NAN, 0, &used); /* confidence decays */
		return MVOD_SCALE_MAP;
	}
	double d = vo->cur->odo - vo->ref->odo;
	if (d > 0) {
		mv->odo_path += d;
		mv->map_path += sqrt(mv->vt[0] * mv->vt[0] + mv->vt[1] * mv->vt[1] +
				     mv->vt[2] * mv->vt[2]);
	}
	return MVOD_SCALE_EXTERNAL;
}

/* --scale external: metres per map unit over the path since the last one; NAN without. */
static double odo_ratio(struct mvod_mapvo *mv)
{
	if (!(mv->odo_path > 0 && mv->map_path > 0))
		return NAN;
	double r = mv->odo_path / mv->map_path;
	/*
	 * Sums from zero at each measurement: kept instead at half or 0.8 of their value (a
	 * longer, exponentially weighted path) cost every clip, exact speed or noisy (KITTI 07
	 * KLT 0.087 -> 0.100 / 0.135 m, with noise 0.267 -> 0.299 / 0.357 m): the map's unit
	 * moves between keyframes, and the older path measures the unit it had then.
	 */
	mv->odo_path = mv->map_path = 0;
	return r;
}

/*
 * Measurement r (metres per map unit, NAN: none) of quality q into the filter; the map
 * rescaled when the filtered unit is off by enough (height: within the bounded gain).
 */
static int apply(struct mvod_vo *vo, double r, double q)
{
	struct mvod_mapvo *mv = vo->mapvo;
	bool external = vo->p.scale_mode == MVOD_SCALE_MODE_EXTERNAL;
	double gain = external ? EXT_GAIN : vo->klt ? PAIR_GAIN : vo->scale.gain;
	double gate = external ? EXT_GATE : vo->scale.gate;
	bool used, was_metric = mvod_scale_filter_metric(&vo->scale);
	mv->unit_log += log(mvod_scale_filter_step_gain(&vo->scale, r / exp(mv->unit_log), q, gain,
							gate, &used));
	double *slot = NULL;
	if (was_metric) {
		slot = mv->rescale_log + mv->kf_scaled++ % MVOD_MAPSCALE_WINDOW;
		*slot = 0;
	}
	mv->n_measured += used;
	double min = external ? EXT_RESCALE_MIN : MAP_RESCALE_MIN;
	if (!used || (was_metric && fabs(mv->unit_log) < min))
		return 0;
	if (slot && !external && mv->n_measured > MVOD_MAPSCALE_WINDOW) {
		mv->unit_log = mvod_scale_bounded(mv->rescale_log, MVOD_MAPSCALE_WINDOW,
						  mv->unit_log, MAP_RESCALE_CAP);
		if (mv->unit_log == 0)
			return 0;
	}
	if (slot)
		*slot = mv->unit_log;
	/*
	 * The first measurement rescales about the world's origin: the chain before it was in
	 * the map's unit and unpublished (vo.c holds it). Later ones about the current camera:
	 * published poses are never rewritten, the path goes on from where it is.
	 */
	double c[3] = {0, 0, 0};
	if (was_metric)
		memcpy(c, vo->pose.t, sizeof(c));
	return rescale(vo, c, exp(mv->unit_log));
}

int mvod_mapscale_keyframe(struct mvod_vo *vo, mvod_map_id kf)
{
	struct mvod_mapvo *mv = vo->mapvo;
	bool external = vo->p.scale_mode == MVOD_SCALE_MODE_EXTERNAL;
	if (vo->p.scale_mode != MVOD_SCALE_MODE_HEIGHT && !external)
		return 0;
	int ret = mvod_mapping_ba_settle(mv);
	if (ret)
		return ret;
	if (external) {
		double r = odo_ratio(mv);
		/* Standing, or no speed: nothing measured, the map keeps its unit. */
		return isnan(r) ? 0 : apply(vo, r, 1.0);
	}
	/*
	 * The last frame's direction of travel (its camera centre from the frame before's: -vt
	 * in its frame) levels the expected ground normal (scale.h). On mvod-synth's KITTI 00
	 * drive, whose ground follows the path, the normal learnt from the ground fits alone
	 * pitched 2.15 deg (median, frames 0-1500) where the camera is pitched 0.88 deg to the
	 * road: the heights ran 5-9 % high. Levelled with the motion: 0.86 deg.
	 */
	double back[3] = {-mv->vt[0], -mv->vt[1], -mv->vt[2]};
	mvod_scale_filter_motion(&vo->scale, back);
	const struct mvod_map_keyframe *k = mvod_map_keyframe(mv->map, kf);
	if (!k)
		return 0;
	double q, r = vo->klt ? pair_ratio(vo, &q) : band_ratio(vo, k, &q);
	return apply(vo, r, q);
}
