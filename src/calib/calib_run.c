/* mvod_calibrate: the source read once, then selection, calibration, rejection and verdict. */
#include "mvod/calibrate.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib/calib_shim.h"
#include "mvod/capture.h"
#include "mvod/log.h"
#include "util/clock.h"
#include "util/errbuf.h"

/* Frames without the board that are examined for what else they show (slow), and how far apart. */
#define MAX_DIAGNOSES 5
#define DIAGNOSE_EVERY 25
/* A ChArUco view needs this many corners by default: 4 fix a homography, 2 more vote down a bad one. */
#define CHARUCO_MIN_CORNERS 6

/* Off-board markers that reject a frame; a single one may be a misread code. */
#define STRAY_MARKERS 2

/* Every detected view; corners of all views in two growing pools. */
struct store {
	int n, cap;
	struct stored {
		int n;
		size_t off;
		int64_t frame;
	} *v;
	int *ids;
	float *xy;
	size_t used, cap_pts;
};

/* What reading the source found besides views: the numbers behind a "no board" message. */
struct scan {
	int w, h;
	double focus;              /* the source's locked lens focus; NaN when it reports none */
	int64_t frames, with_board, with_markers, mislaid, repeats;
	int64_t other_size;        /* frames skipped for another image size than the first's */
	int max_markers, max_corners, max_stray, max_id, diagnosed;
	char seen[128];            /* what a board-less frame showed instead, or "" */
	struct mvod_board fits;    /* the spec that would match it; cols 0: none follows */
	struct mvod_image sample;  /* the frame whose board spans most of the image (report) */
	float sample_extent;
};

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
	if (need <= *cap)
		return 0;
	size_t n = *cap ? *cap : 64;
	while (n < need)
		n *= 2;
	void *q = realloc(*p, n * elem);
	if (!q)
		return -ENOMEM;
	*p = q;
	*cap = n;
	return 0;
}

static int store_add(struct store *s, const struct mvod_calib_found *f, int64_t frame)
{
	size_t cap = (size_t)s->cap;
	int ret = grow((void **)&s->v, &cap, (size_t)s->n + 1, sizeof(*s->v));
	s->cap = (int)cap;
	size_t cap_ids = s->cap_pts, need = s->used + (size_t)f->n;
	if (!ret)
		ret = grow((void **)&s->ids, &cap_ids, need, sizeof(*s->ids));
	if (!ret)
		ret = grow((void **)&s->xy, &s->cap_pts, need, 2 * sizeof(*s->xy));
	if (ret)
		return ret;
	memcpy(s->ids + s->used, f->ids, sizeof(*s->ids) * (size_t)f->n);
	memcpy(s->xy + 2 * s->used, f->xy, 2 * sizeof(*s->xy) * (size_t)f->n);
	s->v[s->n++] = (struct stored){f->n, s->used, frame};
	s->used = need;
	return 0;
}

static struct mvod_calib_obs store_obs(const struct store *s, int i)
{
	return (struct mvod_calib_obs){s->v[i].n, s->ids + s->v[i].off, s->xy + 2 * s->v[i].off,
				       s->v[i].frame};
}

static void store_free(struct store *s)
{
	free(s->v);
	free(s->ids);
	free(s->xy);
}

void mvod_calib_result_free(struct mvod_calib_result *res)
{
	free(res->view_rms_px);
	free(res->view_pose);
	free(res->view_frame);
	res->view_rms_px = res->view_pose = NULL;
	res->view_frame = NULL;
}

static int min_corners(const struct mvod_calib_opts *o)
{
	int all = mvod_board_corner_count(&o->board);
	if (o->min_corners > 0)
		return o->min_corners < all ? o->min_corners : all;
	return o->board.kind == MVOD_BOARD_CHESSBOARD || all < CHARUCO_MIN_CORNERS ? all
										   : CHARUCO_MIN_CORNERS;
}

/* Corners all on one row or one column of the board fix no homography. */
static int spans_plane(const struct mvod_board *b, const struct mvod_calib_found *f)
{
	int nx = b->kind == MVOD_BOARD_CHARUCO ? b->cols - 1 : b->cols;
	int rows = 0, cols = 0;
	for (int i = 1; i < f->n; i++) {
		rows |= f->ids[i] / nx != f->ids[0] / nx;
		cols |= f->ids[i] % nx != f->ids[0] % nx;
	}
	return rows && cols;
}

/* Bounding-box diagonal of the corners over the image diagonal, and their centre. */
static float corner_extent(const struct mvod_calib_obs *v, int w, int h, float *cx, float *cy)
{
	float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
	for (int i = 0; i < v->n; i++) {
		x0 = fminf(x0, v->xy[2 * i]);
		x1 = fmaxf(x1, v->xy[2 * i]);
		y0 = fminf(y0, v->xy[2 * i + 1]);
		y1 = fmaxf(y1, v->xy[2 * i + 1]);
	}
	*cx = 0.5f * (x0 + x1) / (float)w;
	*cy = 0.5f * (y0 + y1) / (float)h;
	return hypotf(x1 - x0, y1 - y0) / hypotf((float)w, (float)h);
}

static int keep_sample(struct scan *sc, const struct mvod_image *img)
{
	int ch = img->fmt == MVOD_PIX_BGR ? 3 : 1;
	if (!sc->sample.data || sc->sample.fmt != img->fmt || sc->sample.w != img->w ||
	    sc->sample.h != img->h) {
		free(sc->sample.data);
		sc->sample = (struct mvod_image){img->w, img->h, img->w * ch, img->fmt,
						 malloc((size_t)img->w * (size_t)img->h * (size_t)ch)};
		if (!sc->sample.data)
			return -ENOMEM;
	}
	for (int y = 0; y < img->h; y++)
		memcpy(sc->sample.data + (size_t)y * (size_t)sc->sample.stride,
		       img->data + (size_t)y * (size_t)img->stride, (size_t)sc->sample.stride);
	return 0;
}

static void note_missing(struct scan *sc, struct mvod_calib_det *det, const struct mvod_image *img,
			 const struct mvod_calib_found *f)
{
	sc->with_markers += f->markers > 0;
	sc->mislaid += f->mislaid;
	sc->max_markers = f->markers > sc->max_markers ? f->markers : sc->max_markers;
	sc->max_corners = f->n > sc->max_corners ? f->n : sc->max_corners;
	sc->max_stray = f->stray > sc->max_stray ? f->stray : sc->max_stray;
	sc->max_id = f->max_id > sc->max_id ? f->max_id : sc->max_id;
	if (sc->seen[0] || f->markers > 0 || sc->diagnosed >= MAX_DIAGNOSES ||
	    (sc->frames - 1) % DIAGNOSE_EVERY != 0)
		return;
	sc->diagnosed++;
	if (mvod_calib_diagnose(det, img, &sc->fits, sc->seen, sizeof(sc->seen)))
		sc->seen[0] = '\0';
}

static int on_frame(const struct mvod_calib_opts *o, struct mvod_calib_det *det,
		    struct mvod_calib_found *f, const struct mvod_frame *fr, struct store *s,
		    struct scan *sc)
{
	const struct mvod_image *img = &fr->img;
	int ret = mvod_calib_detect(det, img, f);
	if (ret || f->repeat) {
		sc->repeats += f->repeat;
		return ret;
	}
	/*
	 * Markers of the dictionary with ids beyond the board mean a larger board than the spec
	 * says: its corners would be placed by the wrong layout.
	 */
	if (f->n < min_corners(o) || !spans_plane(&o->board, f) || f->stray >= STRAY_MARKERS) {
		note_missing(sc, det, img, f);
		return 0;
	}
	sc->with_board++;
	ret = store_add(s, f, fr->index);
	if (ret)
		return ret;
	struct mvod_calib_obs v = store_obs(s, s->n - 1);
	float cx, cy, extent = corner_extent(&v, img->w, img->h, &cx, &cy);
	if (extent > sc->sample_extent) {
		sc->sample_extent = extent;
		ret = keep_sample(sc, img);
	}
	return ret;
}

/* A live camera or a long video says how it is going this often, in seconds. */
#define PROGRESS_S 5.0

/*
 * Ctrl-C ends a live camera's recording, which has no other end: calibrate on it. A file has
 * an end; a calibration on part of it would replace a good --out with a worse one, so nothing
 * is written (--max-frames asks for a part on purpose).
 */
static int stopped_early(const struct mvod_calib_opts *o, struct mvod_source *src,
			 const struct scan *sc, char *err, size_t errlen)
{
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	if (!info.live) {
		return mvod_errf(err, errlen, -EINTR, "%s: interrupted after %lld frames of %s, "
				 "before its end: nothing written, earlier files are as they were; "
				 "let it run to the end, or pass --max-frames N to use only the "
				 "first N frames", o->command, (long long)sc->frames, o->source);
	}
	LOG(INFO, "%s: stopped after %lld frames (%lld with the board); using them (Ctrl-C "
		  "again aborts)", o->command, (long long)sc->frames, (long long)sc->with_board);
	return 0;
}

static int read_all(const struct mvod_calib_opts *o, struct mvod_source *src,
		    struct mvod_calib_det *det, struct store *s, struct scan *sc, char *err,
		    size_t errlen)
{
	int cap = mvod_board_corner_count(&o->board);
	struct mvod_calib_found f = {.ids = malloc(sizeof(int) * (size_t)cap),
				     .xy = malloc(2 * sizeof(float) * (size_t)cap)};
	int ret = f.ids && f.xy ? 0 : -ENOMEM;
	double next_progress = mvod_now_s() + PROGRESS_S;
	while (!ret && !(o->max_frames && sc->frames >= o->max_frames) && !(o->stop && *o->stop)) {
		if (mvod_now_s() >= next_progress) {
			LOG(INFO, "%s: %lld frames read, %lld with the board so far", o->command,
			    (long long)sc->frames, (long long)sc->with_board);
			next_progress += PROGRESS_S;
		}
		struct mvod_frame fr;
		ret = mvod_source_read(src, &fr);
		if (ret == -ENODATA || ret == -EAGAIN || ret == -EINVAL) {
			/* EINVAL: one undecodable frame is skipped, as mvod run does. */
			sc->other_size += ret == -EINVAL && fr.bad == MVOD_BAD_SIZE;
			ret = ret == -ENODATA ? 1 : 0;
			continue;
		}
		if (ret) {
			mvod_errf(err, errlen, ret, "%s: reading frame %lld failed: %s", o->source,
				  (long long)sc->frames, strerror(-ret));
			break;
		}
		sc->frames++;
		ret = on_frame(o, det, &f, &fr, s, sc);
		if (ret)
			mvod_errf(err, errlen, ret, "%s: frame %lld: board detection failed: %s",
				  o->source, (long long)fr.index, strerror(-ret));
	}
	if (!ret && o->stop && *o->stop)
		ret = stopped_early(o, src, sc, err, errlen);
	free(f.ids);
	free(f.xy);
	return ret > 0 ? 0 : ret;
}

/* Why there are not enough views, in terms of what the frames did show. */
static int no_views(const struct mvod_calib_opts *o, const struct scan *sc, int views,
		    int min_views, char *err, size_t errlen)
{
	const struct mvod_board *b = &o->board;
	char spec[128];
	mvod_board_format(b, spec, sizeof(spec));
	int on_board = b->cols * b->rows / 2;
	if (sc->frames == 0)
		return mvod_errf(err, errlen, -ENODATA, "%s: the source has no frames", o->source);
	if (views > 0)
		return mvod_errf(err, errlen, -ENODATA,
				 "found the board in %d of %lld frames; calibration needs at least %d "
				 "views: record more, with the board in different places and tilts",
				 views, (long long)sc->frames, min_views);
	if (b->kind == MVOD_BOARD_CHARUCO && sc->max_stray > 0)
		return mvod_errf(err, errlen, -ENODATA,
				 "found %s markers with ids up to %d but a %dx%d board has %d (ids 0-%d): "
				 "check the board size in --board %s", b->dict_name, sc->max_id, b->cols,
				 b->rows, on_board, on_board - 1, spec);
	if (sc->mislaid > 0)
		return mvod_errf(err, errlen, -ENODATA,
				 "found %s markers in %lld frames, but not arranged as on a %dx%d board "
				 "(COLSxROWS counts squares across, then down): check --board %s",
				 b->dict_name, (long long)sc->mislaid, b->cols, b->rows, spec);
	if (b->kind == MVOD_BOARD_CHARUCO && sc->with_markers > 0)
		return mvod_errf(err, errlen, -ENODATA,
				 "found up to %d board markers in %lld frames but at most %d ChArUco "
				 "corners (a view needs %d): check the square and marker sizes in --board "
				 "%s, or bring the board closer", sc->max_markers,
				 (long long)sc->with_markers, sc->max_corners, min_corners(o), spec);
	char fits[128] = "";
	if (sc->fits.cols > 0)
		mvod_board_format(&sc->fits, fits, sizeof(fits));
	if (sc->seen[0])
		return mvod_errf(err, errlen, -ENODATA, "no %dx%d %s in %lld frames, but found %s: "
				 "%s --board %s", b->cols, b->rows,
				 b->kind == MVOD_BOARD_CHARUCO ? "ChArUco board" : "chessboard",
				 (long long)sc->frames, sc->seen, fits[0] ? "try" : "check",
				 fits[0] ? fits : spec);
	return mvod_errf(err, errlen, -ENODATA,
			 "no board found in %lld frames of %s: check --board %s (%s), the lighting "
			 "and the focus", (long long)sc->frames, o->source, spec,
			 b->kind == MVOD_BOARD_CHARUCO ? "COLSxROWS counts squares"
						       : "COLSxROWS counts inner corners");
}

static int scan_source(const struct mvod_calib_opts *o, int min_views, struct store *s,
		       struct scan *sc, char *err, size_t errlen)
{
	struct mvod_source *src = NULL;
	struct mvod_calib_det *det = NULL;
	int ret = mvod_source_open(o->source, &src, err, errlen);
	if (ret)
		return ret;
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	sc->w = info.width;
	sc->h = info.height;
	sc->focus = info.focus;
	ret = o->check_outputs ? o->check_outputs(o->check_ctx, err, errlen) : 0;
	if (!ret && (ret = mvod_calib_det_create(&o->board, &det)) != 0)
		mvod_errf(err, errlen, ret, "cannot set up the board detector: %s", strerror(-ret));
	else if (!ret)
		ret = read_all(o, src, det, s, sc, err, errlen);
	mvod_calib_det_destroy(det);
	mvod_source_close(src);
	if (!ret && s->n < min_views)
		ret = no_views(o, sc, s->n, min_views, err, errlen);
	return ret;
}

/* All views described for selection, tilts from a rough calibration of all of them. */
static int describe(const struct mvod_calib_opts *o, const struct store *s, const struct scan *sc,
		    struct mvod_calib_obs *obs, struct mvod_calib_view_info *info)
{
	double *rvecs = malloc(sizeof(double) * 3 * (size_t)s->n);
	if (!rvecs)
		return -ENOMEM;
	for (int i = 0; i < s->n; i++)
		obs[i] = store_obs(s, i);
	int ret = mvod_calib_rough_tilts(&o->board, obs, s->n, sc->w, sc->h, rvecs);
	for (int i = 0; !ret && i < s->n; i++) {
		info[i] = (struct mvod_calib_view_info){
			.cells = mvod_calib_cells(obs[i].xy, obs[i].n, sc->w, sc->h),
			.tilt_bin = mvod_calib_tilt_bin(rvecs + 3 * i),
			.corners = obs[i].n,
		};
		info[i].extent = corner_extent(&obs[i], sc->w, sc->h, &info[i].cx, &info[i].cy);
	}
	free(rvecs);
	return ret;
}

struct fitting {
	struct mvod_calib_obs *views; /* selected, then the kept ones first */
	int n;
	struct mvod_calib_fit fit;
};

static int fit_views(const struct mvod_calib_opts *o, const struct scan *sc, struct fitting *ft,
		     char *err, size_t errlen)
{
	return mvod_calib_solve(&o->board, ft->views, ft->n, sc->w, sc->h, o->model, o->rational,
			      &ft->fit, err, errlen);
}

/* Calibrates, drops views above the outlier bound, and calibrates the rest again. */
static int calibrate_views(const struct mvod_calib_opts *o, const struct scan *sc,
			   struct fitting *ft, struct mvod_calib_result *res, char *err, size_t errlen)
{
	int ret = fit_views(o, sc, ft, err, errlen);
	if (ret)
		return ret;
	res->outlier_px = mvod_calib_outlier_px(ft->fit.view_rms_px, ft->n);
	int kept = 0;
	for (int i = 0; i < ft->n; i++)
		kept += ft->fit.view_rms_px[i] <= res->outlier_px;
	if (kept == ft->n || kept < MVOD_CALIB_MIN_VIEWS) {
		/*
		 * Either nothing to drop or too little left: the first fit stands, with every view
		 * still in the order of its per-view errors and poses.
		 */
		return 0;
	}
	kept = 0;
	for (int i = 0; i < ft->n; i++)
		if (ft->fit.view_rms_px[i] <= res->outlier_px)
			ft->views[kept++] = ft->views[i];
	LOG(INFO, "calibrate: dropped %d of %d views above %.3f px and calibrating again",
	    ft->n - kept, ft->n, res->outlier_px);
	ft->n = kept;
	return fit_views(o, sc, ft, err, errlen);
}

/* Views per half of the one-camera check, at least: fewer leave a half's deviations meaningless. */
#define SPLIT_MIN_VIEWS 5

static int by_frame(const void *a, const void *b)
{
	int64_t fa = ((const struct mvod_calib_obs *)a)->frame;
	int64_t fb = ((const struct mvod_calib_obs *)b)->frame;
	return (fa > fb) - (fa < fb);
}

/*
 * Whether the views can be one camera: the first and the second half of them in source order
 * (a folder sorted by name holds one camera's files, then another's: left01..14, right01..14)
 * calibrated apart, and compared (mvod_calib_differ). Pinhole only: the fisheye fit reports
 * no deviations. Says why not in why, else leaves it empty. On OpenCV's left and right
 * chessboard photos the halves give cx 342 and 328 px (about 10 deviations apart) while the
 * blend of both fits at 0.23 px, with per-view errors that do not tell the two apart.
 */
static int split_check(const struct mvod_calib_opts *o, const struct scan *sc,
		       const struct fitting *ft, char *why, size_t len)
{
	int n = ft->n, half = n / 2;
	why[0] = '\0';
	if (!ft->fit.has_std || half < SPLIT_MIN_VIEWS)
		return 0;
	struct mvod_calib_obs *v = malloc(sizeof(*v) * (size_t)n);
	double *work = malloc(sizeof(double) * 7 * (size_t)n); /* per-view rms, then poses */
	int ret = v && work ? 0 : -ENOMEM;
	struct mvod_calib_k4 k[2];
	if (!ret) {
		memcpy(v, ft->views, sizeof(*v) * (size_t)n);
		qsort(v, (size_t)n, sizeof(*v), by_frame);
	}
	for (int p = 0; p < 2 && !ret; p++) {
		struct mvod_calib_fit fit = {.view_rms_px = work, .view_pose = work + n};
		char err[256];
		ret = mvod_calib_solve(&o->board, v + p * half, p ? n - half : half, sc->w, sc->h,
				       o->model, o->rational, &fit, err, sizeof(err));
		k[p] = (struct mvod_calib_k4){{fit.cam.fx, fit.cam.fy, fit.cam.cx, fit.cam.cy},
					      {fit.std_K[0], fit.std_K[1], fit.std_K[2], fit.std_K[3]}};
	}
	char diff[160];
	if (!ret && mvod_calib_differ(&k[0], &k[1], sc->w, diff, sizeof(diff)))
		snprintf(why, len, "the views of frames %lld-%lld and those of frames %lld-%lld give "
			 "%s", (long long)v[0].frame, (long long)v[half - 1].frame,
			 (long long)v[half].frame, (long long)v[n - 1].frame, diff);
	free(v);
	free(work);
	/* A half that does not calibrate on its own says nothing either way. */
	return ret == -ENOMEM ? ret : 0;
}

/* The verdict "not one camera" over any other, when the frames' sizes or the halves say so. */
static void judge_one_camera(const struct scan *sc, const char *why, struct mvod_calib_result *res)
{
	char what[400];
	if (sc->other_size > 0)
		snprintf(what, sizeof(what), "%lld frames of another size than %dx%d were skipped",
			 (long long)sc->other_size, sc->w, sc->h);
	else if (why[0])
		snprintf(what, sizeof(what), "%s", why);
	else
		return;
	res->verdict = MVOD_VERDICT_MIXED;
	snprintf(res->advice, sizeof(res->advice), "These frames cannot all come from one camera: "
		 "%s. The result is a blend of cameras: calibrate each camera on its own frames "
		 "(a folder or a recording per camera).", what);
}

static void finish(const struct fitting *ft, const struct scan *sc, const char *mixed,
		   struct mvod_calib_result *res)
{
	res->cam = ft->fit.cam;
	/* A calibration holds at the focus it was made at; mvod run compares the two. */
	res->cam.has_focus = !isnan(sc->focus);
	res->cam.focus = res->cam.has_focus ? sc->focus : 0;
	res->rms_px = ft->fit.rms_px;
	res->views_used = ft->n;
	res->has_std = ft->fit.has_std;
	memcpy(res->std_K, ft->fit.std_K, sizeof(res->std_K));
	memcpy(res->std_dist, ft->fit.std_dist, sizeof(res->std_dist));
	for (int i = 0; i < ft->n; i++)
		res->view_frame[i] = ft->views[i].frame;
	uint64_t cells = 0;
	for (int i = 0; i < ft->n; i++)
		cells |= mvod_calib_cells(ft->views[i].xy, ft->views[i].n, sc->w, sc->h);
	res->coverage = (double)__builtin_popcountll(cells) / (MVOD_CALIB_CELLS_X * MVOD_CALIB_CELLS_Y);
	res->tilt_span_deg = mvod_calib_tilt_span_deg(res->view_pose, ft->n);
	res->verdict = mvod_calib_judge(ft->n, res->rms_px, res->coverage, res->tilt_span_deg,
					res->advice, sizeof(res->advice));
	judge_one_camera(sc, mixed, res);
}

static int write_report(const struct mvod_calib_opts *o, const struct fitting *ft,
			const struct scan *sc, const struct mvod_calib_result *res, char *err,
			size_t errlen)
{
	struct mvod_calib_report r = {
		.cam = &res->cam, .views = ft->views, .n = ft->n, .view_rms_px = res->view_rms_px,
		.outlier_px = res->outlier_px, .coverage = res->coverage,
		.sample = sc->sample.data ? &sc->sample : NULL, .verdict = res->verdict,
		.advice = res->advice,
	};
	int ret = mvod_calib_report_write(o->report, &r);
	if (ret)
		mvod_errf(err, errlen, ret, "cannot write the report %s: %s", o->report, strerror(-ret));
	return ret;
}

/* Selected views into ft; fewer than the minimum when the frames repeat one another. */
static int select_views(const struct mvod_calib_opts *o, const struct store *s,
			const struct scan *sc, struct fitting *ft, char *err, size_t errlen)
{
	struct mvod_calib_obs *obs = malloc(sizeof(*obs) * (size_t)s->n);
	struct mvod_calib_view_info *info = malloc(sizeof(*info) * (size_t)s->n);
	int *picked = malloc(sizeof(*picked) * (size_t)o->max_views);
	int ret = obs && info && picked ? describe(o, s, sc, obs, info) : -ENOMEM;
	if (!ret)
		ret = mvod_calib_select(info, s->n, o->max_views, picked);
	if (ret >= 0) {
		ft->n = ret;
		for (int i = 0; i < ft->n; i++)
			ft->views[i] = obs[picked[i]];
		ret = ft->n < MVOD_CALIB_MIN_VIEWS
			      ? mvod_errf(err, errlen, -ENODATA,
					  "the board is in %d frames but they show only %d distinct "
					  "views; calibration needs at least %d: move the board between views",
					  s->n, ft->n, MVOD_CALIB_MIN_VIEWS)
			      : 0;
	} else {
		mvod_errf(err, errlen, ret, "view selection failed: %s", strerror(-ret));
	}
	free(obs);
	free(info);
	free(picked);
	return ret;
}

int mvod_calibrate(const struct mvod_calib_opts *o, struct mvod_calib_result *res, char *err,
		   size_t errlen)
{
	memset(res, 0, sizeof(*res));
	struct store s = {0};
	struct scan sc = {.max_id = -1};
	struct fitting ft = {0};
	double t0 = mvod_now_s();
	int ret = scan_source(o, MVOD_CALIB_MIN_VIEWS, &s, &sc, err, errlen);
	double t1 = mvod_now_s();
	res->read_s = t1 - t0;
	res->frames_read = sc.frames;
	res->frames_with_board = sc.with_board;
	res->frames_repeated = sc.repeats;
	if (ret)
		goto out;
	size_t m = (size_t)o->max_views;
	ft.views = malloc(sizeof(*ft.views) * m);
	res->view_rms_px = ft.fit.view_rms_px = malloc(sizeof(double) * m);
	res->view_pose = ft.fit.view_pose = malloc(sizeof(double) * 6 * m);
	res->view_frame = malloc(sizeof(*res->view_frame) * m);
	ret = ft.views && res->view_rms_px && res->view_pose && res->view_frame
		      ? select_views(o, &s, &sc, &ft, err, errlen)
		      : mvod_errf(err, errlen, -ENOMEM, "out of memory for %d views", o->max_views);
	if (ret)
		goto out;
	res->views_selected = ft.n;
	ret = calibrate_views(o, &sc, &ft, res, err, errlen);
	char mixed[320];
	if (!ret && (ret = split_check(o, &sc, &ft, mixed, sizeof(mixed))))
		mvod_errf(err, errlen, ret, "out of memory comparing halves of %d views", ft.n);
	if (ret)
		goto out;
	finish(&ft, &sc, mixed, res);
	res->solve_s = mvod_now_s() - t1;
	if (o->report)
		ret = write_report(o, &ft, &sc, res, err, errlen);
out:
	free(ft.views);
	free(sc.sample.data);
	store_free(&s);
	return ret;
}

void mvod_calib_result_meta(const struct mvod_calib_result *res, const struct mvod_calib_opts *o,
			    struct mvod_calib_meta *meta)
{
	memset(meta, 0, sizeof(*meta));
	meta->rms_px = res->rms_px;
	mvod_board_format(&o->board, meta->board, sizeof(meta->board));
	snprintf(meta->source, sizeof(meta->source), "%s", o->source);
	meta->n_views = res->views_used;
	meta->view_rms_px = res->view_rms_px;
	meta->view_pose = res->view_pose;
	meta->view_frame = res->view_frame;
	meta->has_std = res->has_std;
	memcpy(meta->std_K, res->std_K, sizeof(meta->std_K));
	memcpy(meta->std_dist, res->std_dist, sizeof(meta->std_dist));
	snprintf(meta->verdict, sizeof(meta->verdict), "%s", mvod_calib_verdict_name(res->verdict));
}

int mvod_calib_read_views(const struct mvod_calib_opts *o, int min_views,
			  struct mvod_calib_views *out, char *err, size_t errlen)
{
	memset(out, 0, sizeof(*out));
	struct store *s = calloc(1, sizeof(*s));
	struct scan sc = {.max_id = -1};
	int ret = s ? scan_source(o, min_views, s, &sc, err, errlen)
		    : mvod_errf(err, errlen, -ENOMEM, "out of memory");
	out->pools = s;
	out->w = sc.w;
	out->h = sc.h;
	out->frames = sc.frames;
	free(sc.sample.data);
	if (ret)
		return ret;
	out->obs = malloc(sizeof(*out->obs) * (size_t)s->n);
	if (!out->obs)
		return mvod_errf(err, errlen, -ENOMEM, "out of memory for %d views", s->n);
	for (int i = 0; i < s->n; i++)
		out->obs[i] = store_obs(s, i);
	out->n = s->n;
	return 0;
}

void mvod_calib_views_free(struct mvod_calib_views *v)
{
	if (v->pools)
		store_free(v->pools);
	free(v->pools);
	free(v->obs);
	memset(v, 0, sizeof(*v));
}
