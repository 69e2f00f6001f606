#include "scale.h"

#include <math.h>
#include <string.h>

#include "camera.h"
#include "mvod/geom.h"
#include "util/linalg.h"

/*
 * --scale height: a step's height measurement moves the scale by this fraction (in log
 * space), and one more than 25 % off the prediction is refused. On mvod-synth's street at
 * 0.2 m a step, structure shrinks the step by 5-10 % a step in places: gains 0.2, 0.35 and
 * 0.5 gave SE(3) ATE 1.6 m (14 %), 0.11 m (1.0 %) and 0.07 m (0.6 %) over 11.8 m.
 */
#define HEIGHT_GAIN 0.5
#define HEIGHT_GATE 0.22 /* log(1.25) */
/*
 * --scale height: the first scale is the median of this many measurements (the output held
 * until then). 3 while heights were the fit's own plane's distance: one measurement on KITTI
 * 07's opening creep scattered 30 % and, taken whole, set the unit of all that came before.
 * Along the learnt normal (scale.h) the first measurement alone is the better start: SE(3)
 * ATE at 3 and 1, --camera-height 1.65: 06 two-view 0.642 / 0.408 m, map 0.543 / 0.410 m;
 * 07 two-view 0.409 / 0.394 m, map 0.348 / 0.342 m (drift 1.126 / 1.119).
 */
#define HEIGHT_FIRST 1

void mvod_scale_filter_init(struct mvod_scale_filter *f, double gain, double gate)
{
	*f = (struct mvod_scale_filter){.gain = gain, .gate = gate, .since = -1,
					.ground_n = {0, 1, 0}, .first_n = 1,
					.max_tilt_deg = MVOD_GROUND_MAX_TILT_DEG};
}

double mvod_scale_filter_step_gain(struct mvod_scale_filter *f, double ratio, double quality,
				   double gain, double gate, bool *used)
{
	*used = false;
	if (f->since >= 0)
		f->since++;
	if (!(isfinite(ratio) && ratio > 0))
		return 1.0;
	bool first = f->since < 0;
	if (first) {
		f->first[f->n_first++] = ratio;
		if (f->n_first < f->first_n)
			return 1.0;
		ratio = mvod_median(f->first, f->n_first);
	}
	double r = log(ratio);
	/* Doubling: a scale that structure ran away with (1e13 on mvod-synth's 3.7 km KITTI 00
	 * path at a linear widening) is caught within a few dozen refusals. */
	if (!first && fabs(r) > ldexp(gate, f->refused < 60 ? f->refused : 60)) {
		f->refused++;
		return 1.0;
	}
	f->refused = 0;
	f->since = 0;
	f->quality = quality;
	*used = true;
	return first ? ratio : exp(gain * r);
}

double mvod_scale_filter_step(struct mvod_scale_filter *f, double ratio, double quality,
			      bool *used)
{
	return mvod_scale_filter_step_gain(f, ratio, quality, f->gain, f->gate, used);
}

void mvod_scale_filter_motion(struct mvod_scale_filter *f, const double dir[3])
{
	double len = sqrt(mvod_vec3_dot(dir, dir));
	if (!(isfinite(len) && len > 0) || !(dir[2] > 0))
		return;
	double gain = fmax(1.0 / (f->motion_n + 1), MVOD_MOTION_GAIN), l = 0;
	for (int k = 0; k < 3; k++) {
		f->motion[k] += gain * (dir[k] / len - f->motion[k]);
		l += f->motion[k] * f->motion[k];
	}
	for (int k = 0; k < 3; k++)
		f->motion[k] /= sqrt(l);
	f->motion_n++;
}

double mvod_scale_bounded(const double *recent, int n, double s, double cap)
{
	double sum = 0;
	for (int i = 0; i < n; i++)
		sum += recent[i];
	return s < 0 ? fmax(s, fmin(-cap - sum, 0)) : fmin(s, fmax(cap - sum, 0));
}

bool mvod_scale_filter_metric(const struct mvod_scale_filter *f)
{
	return f->since >= 0;
}

double mvod_scale_filter_confidence(const struct mvod_scale_filter *f)
{
	return f->since < 0 ? 0.0 : f->quality * pow(MVOD_SCALE_DECAY, f->since);
}

/*
 * --scale height: the camera file's mount gives the height when no --camera-height does, and
 * the ground normal's first estimate (the fit searches +-4 deg about it).
 */
static void mount(struct mvod_scale *s, const struct mvod_camera *cam)
{
	if (s->mode != MVOD_SCALE_MODE_HEIGHT || !cam->has_mount)
		return;
	if (!(s->height_m > 0))
		s->height_m = cam->mount_height_m;
	mvod_ground_normal(cam->mount_pitch_deg, cam->mount_roll_deg, s->filter.ground_n);
	s->filter.normal_fits = MVOD_GROUND_MOUNT_FITS;
}

void mvod_scale_init(struct mvod_scale *s, const struct mvod_vo_params *p,
		     const struct mvod_camera *cam)
{
	*s = (struct mvod_scale){.mode = p->scale_mode, .height_m = p->camera_height_m};
	/*
	 * The odometer is metric already: two-view's steps take it whole, never refused (map
	 * mode's keyframe ratios have a gate of their own: map/mapscale.c).
	 */
	if (s->mode == MVOD_SCALE_MODE_EXTERNAL)
		mvod_scale_filter_init(&s->filter, 1.0, INFINITY);
	else
		mvod_scale_filter_init(&s->filter, HEIGHT_GAIN, HEIGHT_GATE);
	s->filter.first_n = s->mode == MVOD_SCALE_MODE_HEIGHT ? HEIGHT_FIRST : 1;
	/* Map mode: no tilt gate (MVOD_GROUND_MAX_TILT_DEG). */
	if (p->mode == MVOD_VO_MAP)
		s->filter.max_tilt_deg = 180;
	mount(s, cam);
}

bool mvod_scale_measured(const struct mvod_scale *s)
{
	return s->mode == MVOD_SCALE_MODE_HEIGHT || s->mode == MVOD_SCALE_MODE_EXTERNAL;
}

void mvod_scale_step(struct mvod_scale *s, double length, double frames)
{
	s->last_step = length / frames;
	s->have_step = true;
}

void mvod_scale_forget_speed(struct mvod_scale *s)
{
	s->have_step = false;
}

void mvod_scale_map_reset(struct mvod_scale *s)
{
	s->unit_log = 0;
	s->odo_path = s->map_path = 0;
}

/*
 * The output's metres per unit (1 once metric, 0 while unknown) and its confidence. With
 * --scale height or external, until the first measurement the position is held at the origin
 * (source NONE, scale 0): the steps so far have no known unit (KITTI 07 creeps 8 frames at
 * 0.1 m a step as 1.0 "m" steps before the road is measured). The chain goes on unpublished
 * and the first measurement rescales it (twoview.c, mapscale.c): published poses are never
 * rewritten (the output policy), the position jumps once, to the metric one.
 */
void mvod_scale_report(const struct mvod_scale *s, struct mvod_vo_result *res)
{
	if (s->mode == MVOD_SCALE_MODE_GT) {
		res->scale = res->scale_confidence = 1.0;
	} else if (s->mode != MVOD_SCALE_MODE_AUTO) {
		bool metric = mvod_scale_filter_metric(&s->filter);
		res->scale = metric ? 1.0 : 0.0;
		res->scale_confidence = mvod_scale_filter_confidence(&s->filter);
		if (metric)
			return;
		memset(res->pose.t, 0, sizeof(res->pose.t));
		res->scale_source = MVOD_SCALE_NONE;
		res->step_m = 0;
	}
}
