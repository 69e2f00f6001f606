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
#include <math.h>
#include <string.h>

#include "internal.h"
#include "mvod/geom.h"
#include "vo/core/camera.h"
#include "vo/geom/ground.h"
#include "vo/geom/motion.h"

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
static double band_ratio(struct mvod_mapmode *m, const struct mvod_map_keyframe *k, double *q)
{
	const struct mvod_vo_ctx *c = m->c;
	float quad[8];
	*q = 0;
	if (mvod_camera_band_quad(c->cam, c->scale->filter.ground_n, quad) != 0)
		return NAN;
	int np = mvod_map_points(m->map, m->ids, m->mp.point_cap), n = 0;
	for (int i = 0; i < np && n < m->cap; i++) {
		double *X = m->pts + 3 * n, uv[2];
		mvod_rigid_apply(k->Rcw, k->tcw, mvod_map_point(m->map, m->ids[i])->pos, X);
		n += mvod_pinhole_pixel(m->K, X, uv) &&
		     mvod_quad_contains(quad, (float)uv[0], (float)uv[1]);
	}
	return mvod_ground_height_ratio(&c->scale->filter, m->pts, n, c->scale->height_m,
					m->scratch, q);
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
static double pair_ratio(struct mvod_mapmode *m, double *q)
{
	const struct mvod_vo_ctx *c = m->c;
	const struct mvod_frames *fr = c->fr;
	const double *vt = m->cam.vt;
	float quad[8];
	*q = 0;
	double len = mvod_tracked_speed(&m->cam);
	if (!(len > 0) || mvod_camera_band_quad(c->cam, c->scale->filter.ground_n, quad) != 0)
		return NAN;
	int n = 0;
	for (int i = 0; i < fr->n_matches && n < m->cap; i++) {
		const struct mvod_keypoint *ka = &fr->ref->f.kp[fr->matches[i].a];
		const struct mvod_keypoint *kb = &fr->cur->f.kp[fr->matches[i].b];
		if (!mvod_quad_contains(quad, kb->x, kb->y))
			continue;
		double x1[2], x2[2], d1, d2;
		mvod_camera_normalise(c->cam, ka->x, ka->y, x1);
		mvod_camera_normalise(c->cam, kb->x, kb->y, x2);
		/* d1 vR x1 + vt = d2 x2 in least squares: the rays' closest points. */
		if (!mvod_triangulate_midpoint(m->cam.vR, vt, x1, x2, &d1, &d2) ||
		    !(d1 > 0 && d2 > 0 && d2 <= MVOD_MOTION_SCALE_DEPTH * len))
			continue;
		double a[3], r1[3] = {x1[0], x1[1], 1}, *X = m->pts + 3 * n, gap = 0;
		mvod_mat3_vec(m->cam.vR, r1, a);
		for (int k = 0; k < 3; k++) {
			double p1 = d1 * a[k] + vt[k], p2 = d2 * (k < 2 ? x2[k] : 1);
			X[k] = 0.5 * (p1 + p2);
			gap += (p1 - p2) * (p1 - p2);
		}
		n += sqrt(gap) * c->cam->fx < PAIR_GAP_PX * d2;
	}
	return mvod_ground_height_ratio(&c->scale->filter, m->pts, n, c->scale->height_m,
					m->scratch, q);
}

/* The map, the tracked frame, its velocity and the pose to publish scaled by s about c. */
static int rescale(struct mvod_mapmode *m, const double c[3], double s, struct mvod_step *st)
{
	int ret = mvod_map_rescale(m->map, c, s);
	if (ret)
		return ret;
	mvod_tracked_rescale(&m->cam, c, s);
	for (int k = 0; k < 3; k++)
		st->pose.t[k] = c[k] + s * (st->pose.t[k] - c[k]);
	m->c->scale->unit_log = 0;
	return 0;
}

enum mvod_scale_source mvod_mapscale_frame(struct mvod_mapmode *m)
{
	struct mvod_scale *sc = m->c->scale;
	const struct mvod_frames *fr = m->c->fr;
	if (sc->mode == MVOD_SCALE_MODE_GT)
		return MVOD_SCALE_GROUND_TRUTH;
	if (sc->mode != MVOD_SCALE_MODE_EXTERNAL)
		return MVOD_SCALE_MAP;
	if (!isfinite(fr->cur->odo)) {
		bool used;
		mvod_scale_filter_step(&sc->filter, NAN, 0, &used); /* confidence decays */
		return MVOD_SCALE_MAP;
	}
	double d = fr->cur->odo - fr->ref->odo;
	if (d > 0) {
		sc->odo_path += d;
		sc->map_path += mvod_tracked_speed(&m->cam);
	}
	return MVOD_SCALE_EXTERNAL;
}

/* --scale external: metres per map unit over the path since the last one; NAN without. */
static double odo_ratio(struct mvod_scale *sc)
{
	if (!(sc->odo_path > 0 && sc->map_path > 0))
		return NAN;
	double r = sc->odo_path / sc->map_path;
	/*
	 * Sums from zero at each measurement: kept instead at half or 0.8 of their value (a
	 * longer, exponentially weighted path) cost every clip, exact speed or noisy (KITTI 07
	 * KLT 0.087 -> 0.100 / 0.135 m, with noise 0.267 -> 0.299 / 0.357 m): the map's unit
	 * moves between keyframes, and the older path measures the unit it had then.
	 */
	sc->odo_path = sc->map_path = 0;
	return r;
}

/*
 * The filtered log unit after a measurement, cut by the bounded gain (height, after the first
 * MVOD_MAPSCALE_WINDOW measurements), into slot: the rescale to apply (0: none).
 */
static double bounded_unit(struct mvod_scale *sc, double *slot, bool external)
{
	if (slot && !external && sc->n_measured > MVOD_MAPSCALE_WINDOW)
		sc->unit_log = mvod_scale_bounded(sc->rescale_log, MVOD_MAPSCALE_WINDOW,
						  sc->unit_log, MAP_RESCALE_CAP);
	if (slot)
		*slot = sc->unit_log;
	return sc->unit_log;
}

/*
 * Measurement r (metres per map unit, NAN: none) of quality q into the filter; the map
 * rescaled when the filtered unit is off by enough (height: within the bounded gain).
 */
static int apply(struct mvod_mapmode *m, double r, double q, struct mvod_step *st)
{
	struct mvod_scale *sc = m->c->scale;
	bool external = sc->mode == MVOD_SCALE_MODE_EXTERNAL;
	double gain = external ? EXT_GAIN : m->c->klt ? PAIR_GAIN : sc->filter.gain;
	double gate = external ? EXT_GATE : sc->filter.gate;
	bool used, was_metric = mvod_scale_filter_metric(&sc->filter);
	sc->unit_log += log(mvod_scale_filter_step_gain(&sc->filter, r / exp(sc->unit_log), q,
							gain, gate, &used));
	double *slot = NULL;
	if (was_metric) {
		slot = sc->rescale_log + sc->kf_scaled++ % MVOD_MAPSCALE_WINDOW;
		*slot = 0;
	}
	sc->n_measured += used;
	double min = external ? EXT_RESCALE_MIN : MAP_RESCALE_MIN;
	if (!used || (was_metric && fabs(sc->unit_log) < min) ||
	    bounded_unit(sc, slot, external) == 0)
		return 0;
	/*
	 * The first measurement rescales about the world's origin: the chain before it was in
	 * the map's unit and unpublished (core/scale.h holds it). Later ones about the current
	 * camera: published poses are never rewritten, the path goes on from where it is.
	 */
	double c[3] = {0, 0, 0};
	if (was_metric)
		memcpy(c, st->pose.t, sizeof(c));
	return rescale(m, c, exp(sc->unit_log), st);
}

int mvod_mapscale_keyframe(struct mvod_mapmode *m, mvod_map_id kf, struct mvod_step *st)
{
	struct mvod_scale *sc = m->c->scale;
	bool external = sc->mode == MVOD_SCALE_MODE_EXTERNAL;
	if (sc->mode != MVOD_SCALE_MODE_HEIGHT && !external)
		return 0;
	int ret = mvod_mapping_ba_settle(m);
	if (ret)
		return ret;
	if (external) {
		double r = odo_ratio(sc);
		/* Standing, or no speed: nothing measured, the map keeps its unit. */
		return isnan(r) ? 0 : apply(m, r, 1.0, st);
	}
	/*
	 * The last frame's direction of travel (its camera centre from the frame before's: -vt
	 * in its frame) levels the expected ground normal (core/scale.h). On mvod-synth's KITTI
	 * 00 drive, whose ground follows the path, the normal learnt from the ground fits alone
	 * pitched 2.15 deg (median, frames 0-1500) where the camera is pitched 0.88 deg to the
	 * road: the heights ran 5-9 % high. Levelled with the motion: 0.86 deg.
	 */
	double back[3] = {-m->cam.vt[0], -m->cam.vt[1], -m->cam.vt[2]};
	mvod_scale_filter_motion(&sc->filter, back);
	const struct mvod_map_keyframe *k = mvod_map_keyframe(m->map, kf);
	if (!k)
		return 0;
	double q, r = m->c->klt ? pair_ratio(m, &q) : band_ratio(m, k, &q);
	return apply(m, r, q, st);
}
