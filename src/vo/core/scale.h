/*
 * The scale of the VO's output: the mode (free, ground truth, camera height, robot speed),
 * the filter that fuses metric measurements (height, the odometer) into a scale that
 * structure alone carries between them, the speed the last steps went at, and map mode's
 * unit. One owner: the modes change it only through these functions.
 */
#ifndef MVOD_VO_CORE_SCALE_H
#define MVOD_VO_CORE_SCALE_H

#include <stdbool.h>
#include <stdint.h>

#include "mvod/calib.h"
#include "mvod/vo_types.h"

/*
 * A mount from the camera file counts as this many fits already learnt: the normal then
 * learns at MVOD_GROUND_NORMAL_GAIN from the first fit on (1 / (9 + 1)).
 */
#define MVOD_GROUND_MOUNT_FITS 9
/*
 * The expected normal does not learn from a ground fit whose own normal is more than this from
 * it (its height along the expected normal still counts). On KITTI 07 the fits' pitch was
 * 1.9 deg on average (sd 1.3) on straight road and 4.0 deg (sd 2.7) in its two turns (3-4 deg
 * of yaw a frame: the band's far part on the kerb and pavement inside the bend); learnt, they
 * pitched the expected normal 4.5 deg and made each height 10-30 % high (steps short) through
 * the second turn and after it. Gates of 1.5, 2, 3 deg and none (BENCHMARKS.md, issue 14's
 * third section): 2 the best on both clips. While heights were the fit's own plane's, a
 * tilted fit was no measurement either; along the expected normal it is one (KITTI 07
 * two-view scale drift 1.123 -> 1.097). Two-view mode only (vo.c): in map mode it made
 * mvod-synth's whole KITTI 00 drive worse (t_rel 6.3 % -> 11.3 %).
 */
#define MVOD_GROUND_MAX_TILT_DEG 2.0
/*
 * The scale filter: each measurement is a ratio, metric value / predicted value (for
 * two-view mode, the step length in metres / the step structure predicts). The first one is
 * taken whole; later ones move the scale by gain in log space, and a ratio beyond the gate
 * (one bad frame: a car's roof taken for the road) is refused, the gate widening with each
 * refusal in a row so that a real change is followed within a few frames.
 */
#define MVOD_SCALE_FIRST_MAX 5
struct mvod_scale_filter {
	double gain;    /* fraction of a measurement's log ratio applied, (0, 1] */
	double gate;    /* largest |log ratio| accepted; INFINITY = all */
	double quality; /* 0-1, of the last accepted measurement */
	int since;      /* steps since the last accepted measurement; -1 before the first */
	int refused;    /* measurements refused in a row */
	double ground_n[3]; /* --scale height: the ground's expected normal in the camera frame
			       (the mount's pitch and roll), from (0, 1, 0) on */
	double max_tilt_deg; /* --scale height: MVOD_GROUND_MAX_TILT_DEG at init; 180: none */
	int tilted;     /* --scale height: ground fits in a row tilted beyond max_tilt_deg
			   from ground_n */
	int normal_fits; /* --scale height: fits ground_n has learnt from (MVOD_GROUND_MOUNT_FITS
			    from a mount); the next moves it by 1 / (normal_fits + 1), at least
			    MVOD_GROUND_NORMAL_GAIN */
	/*
	 * The first scale is the median of this many measurements (1 at init, at most
	 * MVOD_SCALE_FIRST_MAX); until then the output is not metric. Their ratios are alike:
	 * metres per unit of the same chain, which structure carries between them.
	 */
	int first_n;
	int n_first;
	double first[MVOD_SCALE_FIRST_MAX];
	/*
	 * --scale height: the camera's mean direction of travel in its own frame (unit), learnt
	 * from motion steps (mvod_scale_filter_motion), and how many; ground_n is kept
	 * perpendicular to it once there is one (map mode only: mapscale.c).
	 */
	double motion[3];
	int motion_n;
};
void mvod_scale_filter_init(struct mvod_scale_filter *f, double gain, double gate);
/*
 * One step: ratio (NAN when there was no measurement) and its quality (0-1). Returns the
 * factor to multiply the prediction by (1 without an accepted measurement); *used says
 * whether a measurement was accepted.
 */
double mvod_scale_filter_step(struct mvod_scale_filter *f, double ratio, double quality,
			      bool *used);
/*
 * The same step with a gain and a gate of its own for this measurement instead of f->gain and
 * f->gate (map mode's: mapscale.c); the gate still doubles with each refusal in a row.
 */
double mvod_scale_filter_step_gain(struct mvod_scale_filter *f, double ratio, double quality,
				   double gain, double gate, bool *used);
/*
 * --scale height: a motion step's direction of travel in the current camera's frame (any
 * length; ignored when not finite, zero or backwards). The mean direction (the k-th moves it
 * by 1/k, down to MVOD_MOTION_GAIN) is parallel to the road a car drives on, so it carries the
 * camera's pitch to the road better than the ground fits do. Map mode feeds it (mapscale.c);
 * two-view mode does not: levelled with its essential matrices' directions, mvod-synth's
 * KITTI 00 drive went from t_rel 9.01 % to 11.59 %.
 */
#define MVOD_MOTION_GAIN 0.02
void mvod_scale_filter_motion(struct mvod_scale_filter *f, const double dir[3]);
/*
 * Bounded gain (map mode's rescales, mapscale.c): the log rescale s cut so that, with the n
 * recent ones (logs), the unit moves by at most cap (log) either way; 0 when they already
 * moved it that far s's way.
 */
double mvod_scale_bounded(const double *recent, int n, double s, double cap);
/* Whether any measurement was accepted yet (the output is metric). */
bool mvod_scale_filter_metric(const struct mvod_scale_filter *f);
/* 0-1: the last measurement's quality, decaying by MVOD_SCALE_DECAY per step without one. */
#define MVOD_SCALE_DECAY 0.95
double mvod_scale_filter_confidence(const struct mvod_scale_filter *f);

/*
 * --scale height and external, map mode: after this many height measurements, the rescales
 * of any this many keyframes in a row move the map's unit by at most map/mapscale.c's cap.
 */
#define MVOD_MAPSCALE_WINDOW 20

struct mvod_scale {
	enum mvod_scale_mode mode;
	double height_m; /* --scale height: the camera's height above the ground, metres (the
			    parameters', else the camera file's mount) */
	struct mvod_scale_filter filter; /* --scale height, external */
	/*
	 * The speed: the last translation step's length per frame it spanned (scale units), the
	 * length a step without structure (constant speed) or a map rebuilt after a loss takes.
	 */
	double last_step;
	bool have_step;
	/*
	 * Map mode (map/mapscale.c). --scale height: log of the metres per map unit the filtered
	 * height measures (0: the map is metric, or as metric as the chain it was built from);
	 * the log rescale of each of the last MVOD_MAPSCALE_WINDOW keyframes since the first
	 * measurement (0: none), a ring written at kf_scaled's slot, and the measurements taken:
	 * kept across a loss, the published unit carries on into the next map. --scale external:
	 * over the tracked frames since the last measurement that the odometer says moved, its
	 * distance (metres) and the map's steps (map units).
	 */
	double unit_log;
	double rescale_log[MVOD_MAPSCALE_WINDOW];
	uint64_t kf_scaled;
	int n_measured;
	double odo_path, map_path;
};

/*
 * The scale of a VO with parameters p (their scale mode and camera height; p->mode the mode
 * that runs) on camera cam, whose mount (--scale height) gives the height when p gives none
 * and the ground normal's first estimate.
 */
void mvod_scale_init(struct mvod_scale *s, const struct mvod_vo_params *p,
		     const struct mvod_camera *cam);
/* Whether the scale comes from measurements (--scale height, external) through the filter. */
bool mvod_scale_measured(const struct mvod_scale *s);
/* A translation step of length (scale units) over frames frames: the speed from now on. */
void mvod_scale_step(struct mvod_scale *s, double length, double frames);
/* No speed (before a map's first step defines the unit). */
void mvod_scale_forget_speed(struct mvod_scale *s);
/* A map was forgotten: its unit's measurements since the last one go with it. */
void mvod_scale_map_reset(struct mvod_scale *s);
/*
 * res's scale (metres per unit: 1 once metric, 0 while unknown) and its confidence. With
 * --scale height or external, until the first measurement the position is held at the origin
 * (source NONE, step 0): the steps so far have no known unit.
 */
void mvod_scale_report(const struct mvod_scale *s, struct mvod_vo_result *res);

#endif
