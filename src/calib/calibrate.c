#include "mvod/calibrate.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/geom.h"

#define N_CELLS (MVOD_CALIB_CELLS_X * MVOD_CALIB_CELLS_Y)
/* Board tilts binned by 15 deg about each camera axis over +-60 deg: 8 x 8 bins. */
#define TILT_STEP_DEG 15.0
#define TILT_BINS_1D 8
#define N_TILT_BINS (TILT_BINS_1D * TILT_BINS_1D)
/*
 * One fresh tilt bin is worth as much as this many fresh image cells: a board that fills a
 * third of the image covers about 16 cells, and a new tilt constrains the focal length more
 * than a few more cells at an already-seen tilt.
 */
#define CELLS_PER_TILT 8.0
/* Two views whose corner centres and sizes differ by under 2 % of the image, at one tilt, are one view. */
#define DUPLICATE_FRAC 0.02f
/* The verdict's bounds: see mvod_calib_judge. */
#define GOOD_RMS_PX 1.0
#define ENOUGH_VIEWS 15
#define GOOD_COVERAGE 0.5
#define GOOD_TILT_SPAN_DEG 20.0
/* Two parts of the views are two cameras: see mvod_calib_differ. */
#define MIXED_SIGMAS 5.0
#define MIXED_WIDTH_FRAC 0.01
#define MVOD_XSTR(x) #x
#define MVOD_STR(x) MVOD_XSTR(x)

void mvod_calib_opts_default(struct mvod_calib_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->model = MVOD_CAM_PINHOLE_RADTAN;
	o->max_views = 80;
	o->command = "calibrate";
}

const char *mvod_calib_verdict_name(enum mvod_calib_verdict v)
{
	static const char *const names[] = {"good", "poor coverage", "too few views", "high error",
					    "not one camera"};
	return (unsigned)v < sizeof(names) / sizeof(names[0]) ? names[v] : "unknown";
}

struct pt {
	float x, y;
};

static int cmp_pt(const void *a, const void *b)
{
	const struct pt *p = a, *q = b;
	if (p->x != q->x)
		return p->x < q->x ? -1 : 1;
	return (p->y > q->y) - (p->y < q->y);
}

static double cross(struct pt o, struct pt a, struct pt b)
{
	return (double)(a.x - o.x) * (b.y - o.y) - (double)(a.y - o.y) * (b.x - o.x);
}

/* Andrew's monotone chain: the hull of p (sorted in place) into h, counter-clockwise. */
static int convex_hull(struct pt *p, int n, struct pt *h)
{
	qsort(p, (size_t)n, sizeof(*p), cmp_pt);
	int k = 0;
	for (int i = 0; i < n; i++) {
		while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0)
			k--;
		h[k++] = p[i];
	}
	for (int i = n - 2, lower = k + 1; i >= 0; i--) {
		while (k >= lower && cross(h[k - 2], h[k - 1], p[i]) <= 0)
			k--;
		h[k++] = p[i];
	}
	return n > 1 ? k - 1 : n;
}

static int inside_hull(const struct pt *h, int k, struct pt q)
{
	if (k < 3)
		return 0;
	for (int i = 0; i < k; i++)
		if (cross(h[i], h[(i + 1) % k], q) < 0)
			return 0;
	return 1;
}

static int cell_of(float x, float y, int w, int h)
{
	int cx = (int)(x * MVOD_CALIB_CELLS_X / w), cy = (int)(y * MVOD_CALIB_CELLS_Y / h);
	if (cx < 0 || cy < 0 || cx >= MVOD_CALIB_CELLS_X || cy >= MVOD_CALIB_CELLS_Y)
		return -1;
	return cy * MVOD_CALIB_CELLS_X + cx;
}

/*
 * A cell is covered when a corner lies in it or the board spans its centre (the hull of the
 * corners contains it): a large board covers the cells between its sparse corners too.
 */
uint64_t mvod_calib_cells(const float *xy, int n, int w, int h)
{
	struct pt *p = malloc(sizeof(*p) * (size_t)(3 * n + 1));
	if (!p || n < 1) {
		free(p);
		return 0;
	}
	uint64_t cells = 0;
	for (int i = 0; i < n; i++) {
		p[i] = (struct pt){xy[2 * i], xy[2 * i + 1]};
		int c = cell_of(p[i].x, p[i].y, w, h);
		if (c >= 0)
			cells |= 1ull << c;
	}
	struct pt *hull = p + n;
	int k = convex_hull(p, n, hull);
	for (int c = 0; c < N_CELLS; c++) {
		struct pt centre = {((float)(c % MVOD_CALIB_CELLS_X) + 0.5f) * (float)w / MVOD_CALIB_CELLS_X,
				    ((float)(c / MVOD_CALIB_CELLS_X) + 0.5f) * (float)h / MVOD_CALIB_CELLS_Y};
		if (inside_hull(hull, k, centre))
			cells |= 1ull << c;
	}
	free(p);
	return cells;
}

/* The board normal (its z axis) in the camera frame, from a board-to-camera rotation vector. */
static void board_normal(const double rvec[3], double n[3])
{
	double R[9];
	mvod_rot_exp(rvec, R);
	n[0] = R[2];
	n[1] = R[5];
	n[2] = R[8];
}

static int tilt_index(double deg)
{
	int i = (int)floor(deg / TILT_STEP_DEG) + TILT_BINS_1D / 2;
	return i < 0 ? 0 : i >= TILT_BINS_1D ? TILT_BINS_1D - 1 : i;
}

int mvod_calib_tilt_bin(const double rvec[3])
{
	double n[3];
	board_normal(rvec, n);
	/* The normal points away from the camera (z into the board); flip one seen from behind. */
	double s = n[2] < 0 ? -1 : 1;
	double about_y = atan2(s * n[0], s * n[2]) * 180 / M_PI;
	double about_x = atan2(s * n[1], s * n[2]) * 180 / M_PI;
	return tilt_index(about_x) * TILT_BINS_1D + tilt_index(about_y);
}

static double gain(const struct mvod_calib_view_info *v, const int *cover, const int *tilts)
{
	double g = 1.0 / (1 + tilts[v->tilt_bin]);
	for (int c = 0; c < N_CELLS; c++)
		if (v->cells >> c & 1)
			g += 1.0 / (1 + cover[c]) / CELLS_PER_TILT;
	return g;
}

static int is_duplicate(const struct mvod_calib_view_info *a, const struct mvod_calib_view_info *b)
{
	return a->tilt_bin == b->tilt_bin && fabsf(a->cx - b->cx) < DUPLICATE_FRAC &&
	       fabsf(a->cy - b->cy) < DUPLICATE_FRAC && fabsf(a->extent - b->extent) < DUPLICATE_FRAC;
}

/* The not yet considered view of highest gain (more corners breaks ties); -1 when none is left. */
static int best_view(const struct mvod_calib_view_info *v, int n, const char *seen,
		     const int *cover, const int *tilts)
{
	int best = -1;
	double best_gain = -1;
	for (int i = 0; i < n; i++) {
		if (seen[i])
			continue;
		double g = gain(&v[i], cover, tilts);
		if (g > best_gain || (g == best_gain && v[i].corners > v[best].corners)) {
			best = i;
			best_gain = g;
		}
	}
	return best;
}

int mvod_calib_select(const struct mvod_calib_view_info *v, int n, int max, int *picked)
{
	int cover[N_CELLS] = {0}, tilts[N_TILT_BINS] = {0}, k = 0;
	char *seen = calloc((size_t)n + 1, 1);
	if (!seen)
		return -ENOMEM;
	while (k < max) {
		int b = best_view(v, n, seen, cover, tilts);
		if (b < 0)
			break;
		seen[b] = 1;
		int dup = 0;
		for (int j = 0; j < k && !dup; j++)
			dup = is_duplicate(&v[b], &v[picked[j]]);
		if (dup)
			continue;
		picked[k++] = b;
		tilts[v[b].tilt_bin]++;
		for (int c = 0; c < N_CELLS; c++)
			cover[c] += (int)(v[b].cells >> c & 1);
	}
	free(seen);
	return k;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static double median_of(double *v, int n)
{
	qsort(v, (size_t)n, sizeof(*v), cmp_double);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/*
 * median + 3 sigma, sigma from the MAD (1.4826 MAD estimates sigma for normal errors), so a
 * few blurred or mis-detected views cannot widen the bound the way a standard deviation
 * would. The 2 x median floor keeps views of a uniformly good set: when all views are within
 * a few hundredths of a pixel the MAD bound would drop views that are merely average.
 */
double mvod_calib_outlier_px(const double *err, int n)
{
	double *tmp = malloc(sizeof(*tmp) * (size_t)n);
	if (!tmp)
		return INFINITY;
	memcpy(tmp, err, sizeof(*tmp) * (size_t)n);
	double med = median_of(tmp, n);
	for (int i = 0; i < n; i++)
		tmp[i] = fabs(err[i] - med);
	double mad = median_of(tmp, n);
	free(tmp);
	return fmax(med + 3 * 1.4826 * mad, 2 * med);
}

double mvod_calib_tilt_span_deg(const double *pose, int n)
{
	double span = 0;
	for (int i = 0; i < n; i++) {
		double a[3];
		board_normal(pose + 6 * i, a);
		for (int j = i + 1; j < n; j++) {
			double b[3];
			board_normal(pose + 6 * j, b);
			span = fmax(span, mvod_vec3_angle(a, b));
		}
	}
	return span * 180 / M_PI;
}

static void add_advice(char *advice, size_t len, const char *fmt, double v)
{
	size_t used = strlen(advice);
	if (used < len)
		snprintf(advice + used, len - used, fmt, used ? " " : "", v);
}

/*
 * Bounds: an RMS above 1 px means blur, a bent board or a wrong spec (a flat printed board
 * and a sharp camera give 0.1-0.5 px); under 15 views the distortion terms are poorly
 * constrained; corners in under half of the image leave the distortion at the edges a guess;
 * boards all within 20 deg of each other leave the focal length and the distance confounded.
 */
enum mvod_calib_verdict mvod_calib_judge(int views, double rms_px, double coverage,
					 double tilt_span_deg, char *advice, size_t len)
{
	enum mvod_calib_verdict v = MVOD_VERDICT_GOOD;
	advice[0] = '\0';
	if (rms_px > GOOD_RMS_PX) {
		v = MVOD_VERDICT_HIGH_ERROR;
		add_advice(advice, len, "%sThe RMS error is %.2f px (expect under 0.5): avoid motion "
			   "blur (more light, slower moves), keep the board flat, and check --board.", rms_px);
	}
	if (views < ENOUGH_VIEWS) {
		v = v ? v : MVOD_VERDICT_FEW_VIEWS;
		add_advice(advice, len, "%sOnly %.0f views were usable: record at least " 
			   MVOD_STR(ENOUGH_VIEWS) ", with the board in different places and at "
			   "different tilts.", views);
	}
	if (coverage < GOOD_COVERAGE) {
		v = v ? v : MVOD_VERDICT_POOR_COVERAGE;
		add_advice(advice, len, "%sThe corners cover %.0f %% of the image: move the board into "
			   "the corners and edges of the view.", 100 * coverage);
	}
	if (tilt_span_deg < GOOD_TILT_SPAN_DEG) {
		v = v ? v : MVOD_VERDICT_POOR_COVERAGE;
		add_advice(advice, len, "%sTilt the board more: the views span only %.0f deg; turn it "
			   "about 30 deg left, right, up and down.", tilt_span_deg);
	}
	if (v == MVOD_VERDICT_GOOD)
		snprintf(advice, len, "RMS %.2f px over %d views covering %.0f %% of the image, tilts "
			 "spanning %.0f deg.", rms_px, views, 100 * coverage, tilt_span_deg);
	return v;
}

bool mvod_calib_differ(const struct mvod_calib_k4 *a, const struct mvod_calib_k4 *b, int w,
		       char *why, size_t len)
{
	static const char *const names[] = {"fx", "fy", "cx", "cy"};
	int worst = -1;
	double worst_sigmas = 0;
	for (int i = 0; i < 4; i++) {
		double d = fabs(a->k[i] - b->k[i]);
		double sigma = hypot(a->std[i], b->std[i]);
		if (d > MIXED_SIGMAS * sigma && d > MIXED_WIDTH_FRAC * w && d > worst_sigmas * sigma) {
			worst = i;
			worst_sigmas = d / sigma;
		}
	}
	if (worst >= 0)
		snprintf(why, len, "%s %.1f +- %.1f px against %.1f +- %.1f px", names[worst],
			 a->k[worst], a->std[worst], b->k[worst], b->std[worst]);
	return worst >= 0;
}
