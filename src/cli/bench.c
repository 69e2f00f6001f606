/*
 * mvod bench: one configuration's accuracy and speed against ground truth as a table row, or a
 * grid of configurations (--sweep), each run by a fresh mvod process so that none warms caches,
 * page tables or OpenCV's thread pool for the next.
 */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "mvod/capture.h"
#include "mvod/eval.h"
#include "mvod/log.h"
#include "mvod/pipeline.h"
#include "mvod/plot.h"
#include "util/atomic_file.h"
#include "util/errbuf.h"
#include "util/lines.h"
#include "util/output.h"

/*
 * The default sweep: sub-grids joined by '|', each a cross product. Chosen to cover mvod's
 * default (map mode on the klt front end) and two-view mode beside it at three track caps and
 * half the image, ORB's map mode at its defaults, and for the descriptor front end in two-view
 * mode (SIFT has no map mode, and one mode keeps the rows comparable) every detector x
 * matcher with the reference implementation's ratios (ORB 0.7, SIFT 0.6) at two feature caps,
 * its defaults and extremes (10 000 ORB, 50 and 6 000 SIFT), and image scale and blur: 38
 * runs, about 12 minutes on the 160-frame KITTI 07 clip on 2 cores.
 */
static const char default_grid[] =
	"mode=map,twoview;frontend=klt;tracks=250,500,1000"
	"|mode=map,twoview;frontend=klt;tracks=500;resize=0.5"
	"|mode=map;frontend=orb"
	"|mode=twoview;frontend=orb;detector=orb;matcher=bf,bf-cross,bf-ratio,flann,flann-ratio;"
	"features=1000,3000;ratio=0.7"
	"|mode=twoview;frontend=orb;detector=orb;matcher=bf;ratio=0.8;features=2000,10000"
	"|mode=twoview;frontend=orb;detector=orb;matcher=bf;ratio=0.8;features=2000;"
	"resize=0.5,0.25"
	"|mode=twoview;frontend=orb;detector=orb;matcher=bf;ratio=0.8;features=2000;blur=3,9,11"
	"|mode=twoview;frontend=orb;detector=sift;matcher=bf,bf-cross,bf-ratio,flann,flann-ratio;"
	"features=1000,3000;ratio=0.6"
	"|mode=twoview;frontend=orb;detector=sift;matcher=bf-ratio;ratio=0.6;features=50,6000";

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "bench");
	fprintf(out,
"Runs the pipeline (no LCM) against ground truth and prints one table row per configuration:\n"
"detector (klt for the klt front end), matcher, feature cap (klt: track cap), image scale,\n"
"blur, ratio, mode; err_avg and err_max (issue 5's\n"
"per-frame e = (r + d) / (0.5 + r + d)), RPE (rotation deg, direction deg, translation %%),\n"
"ATE (m and %% of the path; SE(3)-aligned, no scale alignment, with --scale gt, height or\n"
"external; Sim(3) with auto), scale drift (largest over smallest path-length ratio to the\n"
"truth of 20-step windows, as eval.py),\n"
"KITTI t_rel (%%) and r_rel (deg/100 m) on paths over 100 m, fps, median and 95th\n"
"percentile frame time and the mean milliseconds of each stage. Every frame needs a\n"
"ground-truth pose: from --gt FILE, or else from the dataset (kitti: with poses/NN.txt\n"
"beside sequences/NN, kitti-raw: with oxts/data/, euroc:, tum: RGB-D with\n"
"groundtruth.txt).\n"
"\n");
	cli_usage_options(out, CLI_SCOPE_BENCH);
	fprintf(out,
"The Output group's files are a single configuration's, not --sweep's; mvod --help-all\n"
"describes every option.\n"
"\n"
"Benchmark:\n"
"  --sweep [GRID]        run a grid of configurations, one fresh process each, one after\n"
"                        the other; print them sorted by err_avg. GRID: axes 'key=v1,v2'\n"
"                        joined by ';' make a cross product; '|' joins cross products. Keys:\n"
"                        mode, frontend, detector, matcher, features, ratio, best, tracks,\n"
"                        resize, blur. The other options apply to every run. Where klt runs\n"
"                        the descriptor keys (detector, matcher, features, ratio, best) are\n"
"                        dropped, where orb runs tracks is, and each configuration that is\n"
"                        left runs once. Default (38 runs, ~12 min on KITTI 07):\n");
	for (const char *g = default_grid; *g;) {
		size_t n = strcspn(g + 1, "|") + 1;
		fprintf(out, "                          %.*s\n", (int)n, g);
		g += n;
	}
	fprintf(out,
"  --report FILE.md      also write the table as Markdown\n"
"  --csv FILE.csv        also write the table as CSV (one header line)\n"
"  --plots DIR           PNGs: path-top.png, path-side.png and errors.png (e, r, d per\n"
"                        frame); with --sweep, sweep.png (err_avg against frame time)\n"
"\n");
	fprintf(out,
"Examples:\n"
"  mvod bench --source kitti:data/sequences/07 --scale gt    (data/poses/07.txt)\n"
"  mvod bench --source euroc:MH_01_easy --scale gt\n"
"  mvod bench --source kitti:data/sequences/07 --gt data/poses/07.txt --scale gt \\\n"
"       --mode twoview --detector sift --matcher flann-ratio --ratio 0.6 --plots out/\n"
"  mvod bench --source kitti:data/sequences/07 --gt data/poses/07.txt --scale gt \\\n"
"       --sweep 'mode=map,twoview;tracks=250,500,1000' --report sweep.md --csv sweep.csv\n"
"  mvod bench --source kitti:data/sequences/07 --gt data/poses/07.txt --scale gt \\\n"
"       --mode twoview --sweep 'detector=orb,sift;matcher=bf-cross,bf-ratio;features=1000,3000'\n"
"\n"
"Exit status: 0 on success, 1 on a run-time fault, 2 on a usage or configuration error (as\n"
"mvod run's: a ground truth or calibration that cannot serve, an output refused at start).\n");
}

/* The table: one column list for Markdown and CSV. */
enum col {
	C_DETECTOR, C_MATCHER, C_FEATURES, C_RESIZE, C_BLUR, C_RATIO, C_MODE, C_FRAMES, C_ERR_AVG,
	C_ERR_MAX, C_RPE_ROT, C_RPE_DIR, C_RPE_PCT, C_ATE_M, C_ATE_PCT, C_DRIFT, C_T_REL, C_R_REL,
	C_FPS, C_MEDIAN, C_P95, C_STAGE0, NCOLS = C_STAGE0 + MVOD_STAGE_COUNT,
};
static const char *const col_md[C_STAGE0] = {
	"detector", "matcher", "features", "resize", "blur", "ratio", "mode", "frames", "err_avg",
	"err_max", "RPE rot deg", "RPE dir deg", "RPE trans %", "ATE m", "ATE %", "scale drift",
	"t_rel %", "r_rel deg/100m", "fps", "median ms", "p95 ms"};
static const char *const col_csv[C_STAGE0] = {
	"detector", "matcher", "features", "resize", "blur", "ratio", "mode", "frames", "err_avg",
	"err_max", "rpe_rot_deg", "rpe_dir_deg", "rpe_trans_pct", "ate_m", "ate_pct",
	"scale_drift", "t_rel_pct", "r_rel_deg_100m", "fps", "frame_ms_median", "frame_ms_p95"};

struct row {
	char f[NCOLS][40];
};

/* --- the sweep grid --- */

#define MAX_AXES 8
#define MAX_CONFIGS 512

/* Grid keys: run options (flags of the config table) that a sweep may vary. */
static const char *const grid_keys[] = {"mode",  "frontend", "detector", "matcher", "features",
					"ratio", "best",     "tracks",   "resize",  "blur", NULL};

/* One axis of a sub-grid: an option and its values (pointers into the grid's copy). */
struct axis {
	const char *key;
	char *values[64];
	int n;
};

/* A configuration: "--key" "value" pairs appended to the child's command line. */
struct config {
	int n;
	char args[2 * MAX_AXES][48];
};

struct sweep {
	struct config cfg[MAX_CONFIGS];
	int n;
};

static int grid_error(const char *what, const char *text)
{
	fprintf(stderr, "%s: --sweep: %s '%s'; see %s --help\n", cli_prog, what, text, cli_prog);
	return -EINVAL;
}

static int config_key(const char *flag)
{
	for (int k = 0; k < mvod_config_nkeys; k++)
		if (strcmp(mvod_config_keys[k].flag, flag) == 0)
			return k;
	return -1;
}

static bool in_list(const char *s, const char *const *list)
{
	for (int i = 0; list[i]; i++)
		if (strcmp(s, list[i]) == 0)
			return true;
	return false;
}

/* Checks key=value with the very parser the option uses, so a typo fails before any run. */
static int check_value(const char *key, const char *value)
{
	if (!in_list(key, grid_keys)) {
		char known[160];
		int len = snprintf(known, sizeof(known), "unknown key (one of");
		for (int i = 0; grid_keys[i] && len < (int)sizeof(known); i++)
			len += snprintf(known + len, sizeof(known) - (size_t)len, "%s%s%s",
					i ? ", " : " ", grid_keys[i], grid_keys[i + 1] ? "" : ")");
		return grid_error(known, key);
	}
	struct mvod_config scratch;
	mvod_config_default(&scratch);
	int ret = cli_parse_key(config_key(key), value, &scratch);
	mvod_config_fini(&scratch);
	return ret;
}

static int parse_axis(char *text, struct axis *a)
{
	char *eq = strchr(text, '=');
	if (!eq || eq == text || !eq[1])
		return grid_error("expected key=value[,value...], found", text);
	*eq = '\0';
	a->key = text;
	a->n = 0;
	for (char *save, *v = strtok_r(eq + 1, ",", &save); v; v = strtok_r(NULL, ",", &save)) {
		if (a->n == 64 || check_value(a->key, v))
			return a->n == 64 ? grid_error("more than 64 values for", a->key) : -EINVAL;
		a->values[a->n++] = v;
	}
	return a->n ? 0 : grid_error("no values for", a->key);
}

/* base with what c sets over it. */
static void row_params(const struct mvod_vo_params *base, const struct config *c,
		       struct mvod_vo_params *out)
{
	struct mvod_config scratch;
	mvod_config_default(&scratch);
	scratch.run.vo = *base;
	char err[256];
	for (int i = 0; i + 1 < c->n; i += 2) /* values were checked by parse_axis */
		mvod_config_set(&scratch, config_key(c->args[i] + 2), c->args[i + 1], err, sizeof(err));
	*out = scratch.run.vo;
}

/*
 * Drops from c the options its front end does not read, so that no two rows differ only by
 * an ignored axis: the descriptor options where klt runs, --tracks where orb does. base: the
 * options every run shares. -EINVAL when what remains clashes with the front end or the mode
 * (--detector from base where klt runs, --tracks from base where orb does, map with SIFT).
 */
static int fit_frontend(const struct mvod_vo_params *base, struct config *c)
{
	static const char *const klt_only[] = {"tracks", NULL};
	struct mvod_vo_params p;
	row_params(base, c, &p);
	enum mvod_frontend fe = mvod_vo_frontend(&p);
	bool klt = fe == MVOD_FRONTEND_KLT;
	const char *const *ignored = klt ? mvod_vo_descriptor_flags : klt_only;
	int n = 0;
	for (int i = 0; i + 1 < c->n; i += 2) {
		/* klt reads neither the descriptor options nor ORB's and SIFT's count, --features */
		const char *key = c->args[i] + 2;
		if (in_list(key, ignored) || (klt && strcmp(key, "features") == 0))
			continue;
		memmove(c->args[n++], c->args[i], sizeof(c->args[0]));
		memmove(c->args[n++], c->args[i + 1], sizeof(c->args[0]));
	}
	c->n = n;
	row_params(base, c, &p);
	p.frontend = fe;
	char err[256];
	if (!mvod_config_check_frontend(&p, err, sizeof(err)))
		return 0;
	fprintf(stderr, "%s: --sweep: %s; see %s --help\n", cli_prog, err, cli_prog);
	return -EINVAL;
}

static bool seen(const struct sweep *sw, const struct config *c)
{
	for (int i = 0; i < sw->n; i++)
		if (&sw->cfg[i] != c && sw->cfg[i].n == c->n &&
		    !memcmp(sw->cfg[i].args, c->args, (size_t)c->n * sizeof(c->args[0])))
			return true;
	return false;
}

/* Appends the cross product of the axes to the sweep, each configuration once. */
static int expand(const struct axis *ax, int n_ax, const struct mvod_vo_params *base,
		  struct sweep *sw)
{
	int idx[MAX_AXES] = {0};
	for (;;) {
		if (sw->n == MAX_CONFIGS)
			return grid_error("more than 512 configurations in", "GRID");
		struct config *c = &sw->cfg[sw->n++];
		c->n = 0;
		for (int k = 0; k < n_ax; k++) {
			snprintf(c->args[c->n++], sizeof(c->args[0]), "--%s", ax[k].key);
			snprintf(c->args[c->n++], sizeof(c->args[0]), "%s", ax[k].values[idx[k]]);
		}
		if (fit_frontend(base, c))
			return -EINVAL;
		if (seen(sw, c))
			sw->n--;
		int k = n_ax - 1;
		while (k >= 0 && ++idx[k] == ax[k].n)
			idx[k--] = 0;
		if (k < 0)
			return 0;
	}
}

static int parse_subgrid(char *text, const struct mvod_vo_params *base, struct sweep *sw)
{
	struct axis ax[MAX_AXES];
	int n = 0;
	for (char *save, *a = strtok_r(text, ";", &save); a; a = strtok_r(NULL, ";", &save)) {
		if (n == MAX_AXES)
			return grid_error("more than 8 axes in", text);
		if (parse_axis(a, &ax[n++]))
			return -EINVAL;
	}
	return n ? expand(ax, n, base, sw) : grid_error("empty grid in", "GRID");
}

/* grid_copy: writable copy of the grid; the configurations point into it until expanded. */
static int parse_grid(char *grid_copy, const struct mvod_vo_params *base, struct sweep *sw)
{
	sw->n = 0;
	char *save;
	for (char *g = strtok_r(grid_copy, "|", &save); g; g = strtok_r(NULL, "|", &save)) {
		/* Each sub-grid has its own strtok_r state; the outer one is kept in save. */
		int ret = parse_subgrid(g, base, sw);
		if (ret)
			return ret;
	}
	return sw->n ? 0 : grid_error("empty grid", "");
}

struct bench {
	struct mvod_config cfg; /* the run options, from the same table as mvod run's */
	const char *report, *csv, *plots, *grid;
	int quiet;
	int argc;
	char **argv;    /* normalised: --sweep GRID as --sweep=GRID */
	bool *own_arg;  /* argv[i] belongs to a bench option, which no sweep child gets */
	char *grid_copy;  /* the grid, cut up by parse_grid */
	struct sweep *sw; /* with --sweep: the configurations */
};

enum bench_opt_id { OPT_SWEEP = CLI_OPT_OWN, OPT_REPORT, OPT_CSV, OPT_PLOTS };

static const struct option bench_own_opts[] = {
	{"sweep", optional_argument, NULL, OPT_SWEEP},
	{"report", required_argument, NULL, OPT_REPORT},
	{"csv", required_argument, NULL, OPT_CSV},
	{"plots", required_argument, NULL, OPT_PLOTS},
	{NULL, 0, NULL, 0},
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct bench *b = ctx;
	/* getopt has just consumed the option, and its argument when given separately. */
	b->own_arg[optind - 1] = true;
	if (arg && arg == b->argv[optind - 1])
		b->own_arg[optind - 2] = true;
	switch (id) {
	case OPT_SWEEP: b->grid = arg ? arg : default_grid; return 0;
	case OPT_REPORT: b->report = arg; return 0;
	case OPT_CSV: b->csv = arg; return 0;
	case OPT_PLOTS: b->plots = arg; return 0;
	}
	return -ENOENT;
}

/* getopt takes an optional argument only as --sweep=GRID; the form is --sweep GRID. */
static int normalise_argv(struct bench *b, int argc, char **argv)
{
	b->argv = calloc((size_t)argc + 1, sizeof(char *));
	b->own_arg = calloc((size_t)argc + 1, sizeof(bool));
	if (!b->argv || !b->own_arg)
		return -ENOMEM;
	for (int i = 0; i < argc; i++) {
		if (strcmp(argv[i], "--sweep") == 0 && i + 1 < argc && argv[i + 1][0] != '-') {
			if (asprintf(&b->argv[b->argc++], "--sweep=%s", argv[++i]) < 0)
				return -ENOMEM;
		} else {
			b->argv[b->argc++] = strdup(argv[i]);
		}
		if (!b->argv[b->argc - 1])
			return -ENOMEM;
	}
	return 0;
}

static void bench_free(struct bench *b)
{
	free(b->grid_copy);
	free(b->sw);
	for (int i = 0; b->argv && i < b->argc; i++)
		free(b->argv[i]);
	free(b->argv);
	free(b->own_arg);
	mvod_config_fini(&b->cfg);
}

/* A flag of the config table that only mvod run has a use for would be ignored here: refuse it. */
static int reject_run_only(const struct mvod_config *cfg)
{
	for (int k = 0; k < mvod_config_nkeys; k++) {
		if (!mvod_config_keys[k].run_only || !(cfg->set & (1ULL << k)))
			continue;
		fprintf(stderr, "%s: --%s applies only to mvod run (the bench publishes nothing over "
				"LCM and evaluates the camera's poses in the camera frame); see %s "
				"--help\n", cli_prog, mvod_config_keys[k].flag, cli_prog);
		return -EINVAL;
	}
	return 0;
}

/* 0 to run, 1 when help/version was printed, -EINVAL on a usage error. */
static int parse_cli(int argc, char **argv, struct bench *b)
{
	mvod_config_default(&b->cfg);
	if (normalise_argv(b, argc, argv))
		return -ENOMEM;
	int ret = cli_getopt(b->argc, b->argv, bench_own_opts, parse_own, b, usage, &b->cfg,
			     &b->quiet);
	if (!ret)
		ret = reject_run_only(&b->cfg);
	if (!ret)
		ret = cli_check_frontend(&b->cfg);
	if (ret)
		return ret;
	mvod_config_finish(&b->cfg);
	mvod_config_apply_log(&b->cfg);
	/* A dataset may carry its ground truth; whether this one does, opening it tells. */
	if (!b->cfg.run.source || (!b->cfg.run.gt && !mvod_source_may_have_gt(b->cfg.run.source))) {
		fprintf(stderr, "%s: --source URI and --gt FILE are required (kitti:, euroc: and "
				"tum: sequences may carry their own), e.g. --source kitti:SEQDIR --gt "
				"poses.txt; see %s --help\n", cli_prog, cli_prog);
		return -EINVAL;
	}
	b->cfg.run.require_gt = 1;
	if (!b->grid)
		return 0;
	/* Every child of a sweep would write the same file over the last one's. */
	if (b->cfg.run.trajectory || b->cfg.run.plot) {
		fprintf(stderr, "%s: --%s writes one run's poses: give it without --sweep (the "
				"sweep's own outputs are --report, --csv and --plots); see %s --help\n",
			cli_prog, b->cfg.run.trajectory ? "trajectory" : "plot", cli_prog);
		return -EINVAL;
	}
	b->grid_copy = strdup(b->grid);
	b->sw = calloc(1, sizeof(*b->sw));
	return b->grid_copy && b->sw ? parse_grid(b->grid_copy, &b->cfg.run.vo, b->sw) : -ENOMEM;
}

/* --- one configuration --- */

/* Every frame's estimated and ground-truth pose, kept for the errors that need the whole run. */
struct collect {
	int n, cap;
	struct mvod_pose *est, *gt;
};

/*
 * Grows by doubling: a handful of reallocations over a run, none in the VO itself. The bench
 * needs every pose (KITTI segments reach 800 m back); the daemon keeps none of them.
 */
static int collect_frame(void *ctx, const struct mvod_frame_out *f)
{
	struct collect *c = ctx;
	if (c->n == c->cap) {
		int cap = c->cap ? 2 * c->cap : 1024;
		struct mvod_pose *e = realloc(c->est, (size_t)cap * sizeof(*e));
		if (e)
			c->est = e;
		struct mvod_pose *g = realloc(c->gt, (size_t)cap * sizeof(*g));
		if (g)
			c->gt = g;
		if (!e || !g)
			return -ENOMEM;
		c->cap = cap;
	}
	c->est[c->n] = f->res->pose;
	c->gt[c->n] = *f->gt; /* require_gt: every frame has one */
	c->n++;
	return 0;
}

/* The bench's sink: every estimated pose and its ground truth, for the whole-run errors. */
static const struct mvod_sink_ops collect_ops = {.name = "bench", .frame = collect_frame};

/*
 * Errors over the whole run, from the collected poses, and the per-frame series behind them,
 * which the plots draw: each computed once.
 */
struct whole_run {
	struct mvod_rpe rpe;        /* as the summary's, on the metric estimate */
	double drift;               /* NAN when undefined */
	struct mvod_kitti_rel krel; /* NAN fields on paths of 100 m or less */
	int n;                      /* frames */
	double *pe, *pg;            /* positions, n x 3: the metric estimate, the ground truth */
	double *dist;               /* distance along the ground truth to each frame, m */
	double *e, *r, *d;          /* mvod_frame_err per frame; 0 for the first, which has none */
	double *buf;                /* owns all of the above */
};

static int whole_run_alloc(struct whole_run *w, int n)
{
	size_t m = (size_t)(n ? n : 1);
	*w = (struct whole_run){.n = n, .buf = calloc(m * 10, sizeof(double))};
	if (!w->buf)
		return -ENOMEM;
	w->pe = w->buf;
	w->pg = w->pe + 3 * m;
	w->dist = w->pg + 3 * m;
	w->e = w->dist + m;
	w->r = w->e + m;
	w->d = w->r + m;
	return 0;
}

static void positions(const struct mvod_pose *p, int n, double *out)
{
	for (int i = 0; i < n; i++)
		memcpy(out + 3 * i, p[i].t, sizeof(p[i].t));
}

/*
 * A free-scale estimate is in units of its first step, but d, the ATE and the KITTI errors are
 * in metres: its translations take the scale of the Sim(3) alignment the ATE used (1 with
 * --scale gt), and every error below, and the plots, see that metric estimate.
 */
static int whole_run_errors(struct collect *c, double scale, struct whole_run *w)
{
	int ret = whole_run_alloc(w, c->n);
	if (ret)
		return ret;
	for (int i = 0; i < c->n; i++)
		for (int k = 0; k < 3; k++)
			c->est[i].t[k] *= isfinite(scale) ? scale : 1;
	for (int i = 1; i < c->n; i++) {
		struct mvod_frame_err fe = mvod_rpe_add(&w->rpe, &c->est[i - 1], &c->est[i],
							&c->gt[i - 1], &c->gt[i]);
		w->e[i] = fe.e;
		w->r[i] = fe.r_deg;
		w->d[i] = fe.d_m;
	}
	mvod_rpe_finish(&w->rpe);
	positions(c->est, c->n, w->pe);
	positions(c->gt, c->n, w->pg);
	if (mvod_scale_drift(w->pe, w->pg, c->n, &w->drift))
		w->drift = NAN;
	mvod_kitti_segments(c->est, c->gt, c->n, w->dist, &w->krel);
	return 0;
}

static void cell(struct row *r, enum col c, const char *fmt, double v)
{
	if (isfinite(v))
		snprintf(r->f[c], sizeof(r->f[c]), fmt, v);
	else
		strcpy(r->f[c], "-");
}

static void config_cells(const struct mvod_vo_params *p, struct row *r)
{
	snprintf(r->f[C_DETECTOR], sizeof(r->f[0]), "%s", mvod_detector_name(p->detector));
	if (p->matcher == MVOD_MATCHER_BF_CROSS)
		snprintf(r->f[C_MATCHER], sizeof(r->f[0]), "bf-cross best %d", p->best_n);
	else
		snprintf(r->f[C_MATCHER], sizeof(r->f[0]), "%s", mvod_matcher_kind_name(p->matcher));
	cell(r, C_FEATURES, "%.0f", p->max_features);
	cell(r, C_RESIZE, "%g", p->resize);
	cell(r, C_BLUR, "%.0f", p->blur_ksize);
	cell(r, C_RATIO, "%g", mvod_matcher_uses_ratio(p->matcher) ? p->ratio : NAN);
	snprintf(r->f[C_MODE], sizeof(r->f[0]), "%s", mvod_vo_mode_names[p->mode]);
	if (mvod_vo_frontend(p) == MVOD_FRONTEND_KLT) { /* no descriptors, no matcher: the track cap */
		strcpy(r->f[C_DETECTOR], "klt");
		strcpy(r->f[C_MATCHER], "-");
		strcpy(r->f[C_RATIO], "-");
		cell(r, C_FEATURES, "%.0f", p->max_tracks);
	}
}

static void fill_row(const struct mvod_run_opts *o, const struct mvod_run_summary *s,
		     const struct whole_run *w, struct row *r)
{
	config_cells(&o->vo, r);
	cell(r, C_FRAMES, "%.0f", (double)s->frames);
	cell(r, C_ERR_AVG, "%.3f", w->rpe.err_avg);
	cell(r, C_ERR_MAX, "%.3f", w->rpe.err_max);
	cell(r, C_RPE_ROT, "%.3f", w->rpe.rot_deg_mean);
	cell(r, C_RPE_DIR, "%.2f", w->rpe.n_dir ? w->rpe.dir_deg_mean : NAN);
	cell(r, C_RPE_PCT, "%.1f", w->rpe.n_pct ? w->rpe.trans_pct_mean : NAN);
	cell(r, C_ATE_M, "%.3f", s->ate_rmse_m);
	cell(r, C_ATE_PCT, "%.2f", 100 * s->ate_rmse_m / s->path_len_m);
	/* A free-scale run can blow its scale up by orders of magnitude: keep the cell short. */
	cell(r, C_DRIFT, fabs(w->drift) < 1e3 ? "%.3f" : "%.2e", w->drift);
	cell(r, C_T_REL, "%.2f", w->krel.t_rel_pct);
	cell(r, C_R_REL, "%.3f", w->krel.r_rel_deg_100m);
	cell(r, C_FPS, "%.1f", s->fps);
	cell(r, C_MEDIAN, "%.1f", s->frame_ms_median);
	cell(r, C_P95, "%.1f", s->frame_ms_p95);
	for (int k = 0; k < MVOD_STAGE_COUNT; k++)
		cell(r, (enum col)(C_STAGE0 + k), "%.2f", s->stage_ms_mean[k]);
}

/* --- the table as text --- */

static void header_name(int c, bool csv, char *buf, size_t len)
{
	if (c < C_STAGE0)
		snprintf(buf, len, "%s", csv ? col_csv[c] : col_md[c]);
	else
		snprintf(buf, len, csv ? "%s_ms" : "%s ms", mvod_stage_names[c - C_STAGE0]);
}

static void format_table(FILE *f, const struct row *rows, int n, bool csv)
{
	const char *sep = csv ? "," : " | ", *open = csv ? "" : "| ", *close = csv ? "\n" : " |\n";
	char name[40];
	fputs(open, f);
	for (int c = 0; c < NCOLS; c++) {
		header_name(c, csv, name, sizeof(name));
		fprintf(f, "%s%s", c ? sep : "", name);
	}
	fputs(close, f);
	if (!csv) {
		for (int c = 0; c < NCOLS; c++)
			fputs(c < C_FRAMES ? "|---" : "|--:", f);
		fputs("|\n", f);
	}
	for (int i = 0; i < n; i++) {
		fputs(open, f);
		for (int c = 0; c < NCOLS; c++)
			fprintf(f, "%s%s", c ? sep : "", rows[i].f[c]);
		fputs(close, f);
	}
}

/* Prints the Markdown table and writes --report / --csv, each whole or not at all. */
static int output_table(const struct bench *b, const struct row *rows, int n)
{
	int ret = 0;
	bool stdout_failed = false;
	for (int csv = 0; csv < 2; csv++) {
		char *text = NULL;
		size_t len = 0;
		FILE *f = open_memstream(&text, &len);
		if (!f)
			return -ENOMEM;
		format_table(f, rows, n, csv);
		if (fclose(f))
			return -ENOMEM;
		const char *path = csv ? b->csv : b->report;
		if (!b->quiet && !stdout_failed &&
		    (printf("%s%s", csv ? "\n" : "", text) < 0 || fflush(stdout) != 0)) {
			/* A closed pipe or a full disk: the table is the bench's result, so it fails. */
			LOG(ERROR, "cannot write the table to standard output: %s", strerror(errno));
			stdout_failed = true;
			ret = ret ? ret : -EIO;
		}
		int wret = path ? mvod_write_replace(path, text, len) : 0;
		if (wret)
			LOG(ERROR, "cannot write %s: %s", path, strerror(-wret));
		ret = ret ? ret : wret;
		free(text);
	}
	return ret;
}

/* --- plots of one run --- */

static int plot_dir(const char *dir)
{
	if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
		int ret = -errno;
		LOG(ERROR, "cannot create plot directory %s: %s", dir, strerror(errno));
		return ret;
	}
	return 0;
}

static int plot_failed(const char *path, int ret)
{
	if (ret)
		LOG(ERROR, "cannot write plot %s: %s", path, strerror(-ret));
	return ret;
}

/*
 * Side view: height (-y, camera y points down) over the distance driven along the ground
 * truth, so a path that turns still reads left to right.
 */
static int plot_side(const char *path, const char *title, const struct whole_run *w)
{
	int n = w->n;
	double *buf = malloc((size_t)(n ? n : 1) * 2 * sizeof(double));
	if (!buf)
		return -ENOMEM;
	double *ey = buf, *gy = buf + n;
	for (int i = 0; i < n; i++) {
		ey[i] = -w->pe[3 * i + 1];
		gy[i] = -w->pg[3 * i + 1];
	}
	struct mvod_plot_series ser[2] = {
		{"estimate", w->dist, ey, n, MVOD_PLOT_LINE, NULL},
		{"ground truth", w->dist, gy, n, MVOD_PLOT_DASHED, NULL},
	};
	struct mvod_plot_panel p = {"distance along the ground truth [m]", "height, -y [m]", ser, 2, false};
	int ret = mvod_plot_chart(path, title, &p, 1);
	free(buf);
	return ret;
}

/* e, r and d per frame in three panels over the frame index. */
static int plot_errors(const char *path, const char *title, const struct whole_run *w)
{
	int n = w->n;
	double *x = malloc((size_t)(n ? n : 1) * sizeof(double));
	if (!x)
		return -ENOMEM;
	for (int i = 0; i < n; i++)
		x[i] = i;
	struct mvod_plot_series s[3] = {
		{"e = (r + d) / (0.5 + r + d)", x, w->e, n, MVOD_PLOT_LINE, NULL},
		{"r: heading error", x, w->r, n, MVOD_PLOT_LINE, NULL},
		{"d: step error", x, w->d, n, MVOD_PLOT_LINE, NULL},
	};
	struct mvod_plot_panel p[3] = {
		{"frame", "e", &s[0], 1, false},
		{"frame", "r [deg]", &s[1], 1, false},
		{"frame", "d [m]", &s[2], 1, false},
	};
	int ret = mvod_plot_chart(path, title, p, 3);
	free(x);
	return ret;
}

/*
 * The plotted estimate is the one the ATE measured: moved onto the ground truth by SE(3), or
 * by Sim(3) for a free-scale run (whose units are its first step). heading: the last
 * orientation, turned with it.
 */
static void align(double *pe, const double *pg, int n, bool sim3, const double last_R[9],
		  double heading[9])
{
	double R[9], t[3], s;
	memcpy(heading, last_R, 9 * sizeof(double));
	if (mvod_umeyama(pe, pg, n, sim3, R, t, &s) != 0)
		return;
	mvod_sim3_apply(R, t, s, pe, n);
	mvod_mat3_mul(R, last_R, heading);
}

/* Draws w's series; the estimate's positions are aligned in place, so the row comes first. */
static int run_plots(const struct bench *b, const struct collect *c, struct whole_run *w,
		     const struct row *row)
{
	char path[4096], title[256];
	double heading[9];
	int ret = plot_dir(b->plots);
	if (ret)
		return ret;
	align(w->pe, w->pg, w->n, b->cfg.run.vo.scale_mode == MVOD_SCALE_MODE_AUTO,
	      c->est[c->n - 1].R, heading);
	snprintf(title, sizeof(title), "%s %s, %s features: err_avg %s, ATE %s m",
		 row->f[C_DETECTOR], row->f[C_MATCHER], row->f[C_FEATURES], row->f[C_ERR_AVG],
		 row->f[C_ATE_M]);
	snprintf(path, sizeof(path), "%s/path-top.png", b->plots);
	ret = plot_failed(path, mvod_plot_topdown(path, title, w->pe, w->n, heading, w->pg, w->n, mvod_plot_unit(true)));
	snprintf(path, sizeof(path), "%s/path-side.png", b->plots);
	ret = ret ? ret : plot_failed(path, plot_side(path, title, w));
	snprintf(path, sizeof(path), "%s/errors.png", b->plots);
	ret = ret ? ret : plot_failed(path, plot_errors(path, title, w));
	return ret;
}

/* One run and its row: the exit status (cli_run_status for the run's own failures). */
static int bench_one(const struct bench *b)
{
	struct collect c = {0};
	struct mvod_run_opts o = b->cfg.run;
	struct mvod_sink collector = {&collect_ops, &c};
	o.sinks = &collector;
	o.n_sinks = 1;
	struct mvod_run_summary s;
	struct whole_run w = {0};
	struct row row;
	int ret = mvod_run(&o, NULL, NULL, &s);
	int status = cli_run_status(ret, &s);
	if (!ret && c.n < 2) {
		LOG(ERROR, "%s: %d frame(s): a benchmark needs at least two", o.source, c.n);
		ret = -ENODATA;
	}
	if (!ret && s.gt_static)
		LOG(WARN, "%s: the ground truth does not move, but the estimate went %.3f (farthest "
			  "%.3f from the start): ATE and the KITTI errors are undefined (\"-\")",
		    o.source, s.est_len, s.est_extent);
	if (!ret)
		ret = whole_run_errors(&c, s.ate_scale, &w);
	if (!ret) {
		fill_row(&o, &s, &w, &row);
		ret = output_table(b, &row, 1);
		if (b->plots) {
			int pret = run_plots(b, &c, &w, &row);
			ret = ret ? ret : pret;
		}
	}
	free(w.buf);
	free(c.est);
	free(c.gt);
	return status ? status : ret ? EXIT_FAILURE : EXIT_SUCCESS;
}

/* --- the sweep --- */

/* The child's command line: mvod bench, the shared options, the configuration, --csv tmp. */
static char **child_argv(const struct bench *b, const struct config *c, const char *csv)
{
	char **argv = calloc((size_t)(b->argc + c->n + 5), sizeof(char *));
	if (!argv)
		return NULL;
	int n = 0;
	argv[n++] = "mvod";
	argv[n++] = "bench";
	for (int i = 1; i < b->argc; i++)
		if (!b->own_arg[i])
			argv[n++] = b->argv[i];
	for (int i = 0; i < c->n; i++)
		argv[n++] = (char *)c->args[i];
	argv[n++] = "--csv";
	argv[n++] = (char *)csv;
	argv[n++] = "-q";
	return argv;
}

/* Runs one configuration in a fresh process; 0 when it exited 0. */
static int run_child(char **argv)
{
	fflush(NULL);
	pid_t pid = fork();
	if (pid < 0)
		return -errno;
	if (pid == 0) {
		execv("/proc/self/exe", argv);
		fprintf(stderr, "%s: cannot run /proc/self/exe: %s\n", cli_prog, strerror(errno));
		_exit(127);
	}
	int st;
	while (waitpid(pid, &st, 0) < 0)
		if (errno != EINTR)
			return -errno;
	return WIFEXITED(st) && WEXITSTATUS(st) == 0 ? 0 : -ECHILD;
}

/* The data line (the second) of a one-row CSV the child wrote, split into cells: 1 when whole. */
static int split_row(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct row *r = ctx;
	if (lineno < 2)
		return 0;
	int c = 0;
	for (char *save, *t = strtok_r(line, ",", &save); t && c < NCOLS;
	     t = strtok_r(NULL, ",", &save))
		snprintf(r->f[c++], sizeof(r->f[0]), "%s", t);
	return c == NCOLS ? 1
			  : mvod_errf(err, errlen, -EINVAL, "line %zu: %d cells, not %d", lineno, c,
				      NCOLS);
}

static int read_row(const char *path, struct row *r)
{
	char err[1024] = "";
	r->f[NCOLS - 1][0] = '\0';
	int ret = mvod_lines_each(path, "mvod bench CSV", split_row, r, err, sizeof(err));
	if (!ret && !r->f[NCOLS - 1][0])
		ret = mvod_errf(err, sizeof(err), -EINVAL, "%s holds no row", path);
	if (ret)
		LOG(ERROR, "%s", err);
	return ret;
}

static double num(const struct row *r, enum col c)
{
	char *end;
	double v = strtod(r->f[c], &end);
	return end == r->f[c] ? NAN : v;
}

/* By err_avg, a missing value last. */
static int by_err_avg(const void *pa, const void *pb)
{
	double a = num(pa, C_ERR_AVG), b = num(pb, C_ERR_AVG);
	if (isnan(a) || isnan(b))
		return isnan(a) - isnan(b);
	return (a > b) - (a < b);
}

static void config_label(const struct config *c, char *buf, size_t len)
{
	size_t w = 0;
	buf[0] = '\0';
	for (int i = 0; i + 1 < c->n && w < len; i += 2)
		w += (size_t)snprintf(buf + w, len - w, "%s%s=%s", i ? " " : "", c->args[i] + 2,
				      c->args[i + 1]);
}

static int sweep_one(const struct bench *b, const struct config *c, const char *tmp, int i,
		     int n, struct row *r)
{
	char label[512];
	config_label(c, label, sizeof(label));
	fprintf(stderr, "%s: [%d/%d] %s\n", cli_prog, i + 1, n, label);
	char **argv = child_argv(b, c, tmp);
	if (!argv)
		return -ENOMEM;
	int ret = run_child(argv);
	free(argv);
	if (!ret)
		ret = read_row(tmp, r);
	if (ret)
		LOG(ERROR, "sweep stopped: %s failed%s", label,
		    ret == -ECHILD ? " (its reason is above)" : ": no result row");
	else
		fprintf(stderr, "%s:         err_avg %s, %s fps\n", cli_prog, r->f[C_ERR_AVG],
			r->f[C_FPS]);
	unlink(tmp);
	return ret;
}

/*
 * "sift flann-ratio 0.6, 3000, twoview": the image scale, blur and mode where they are not 1, 0
 * and map.
 */
static void point_text(const struct row *r, char *buf, size_t len)
{
	bool ratio = strcmp(r->f[C_RATIO], "-") != 0, resized = strcmp(r->f[C_RESIZE], "1") != 0;
	bool blurred = strcmp(r->f[C_BLUR], "0") != 0, tv = strcmp(r->f[C_MODE], "twoview") == 0;
	snprintf(buf, len, "%s %s%s%s, %s%s%s%s%s%s", r->f[C_DETECTOR], r->f[C_MATCHER],
		 ratio ? " " : "", ratio ? r->f[C_RATIO] : "", r->f[C_FEATURES],
		 resized ? ", x" : "", resized ? r->f[C_RESIZE] : "", blurred ? ", blur " : "",
		 blurred ? r->f[C_BLUR] : "", tv ? ", twoview" : "");
}

/* One point per configuration: err_avg against median frame time. */
static int sweep_plot(const struct bench *b, const struct row *rows, int n)
{
	int ret = plot_dir(b->plots);
	if (ret)
		return ret;
	double *x = malloc((size_t)n * 2 * sizeof(double)), *y = x ? x + n : NULL;
	char **labels = calloc((size_t)n, sizeof(char *));
	char(*text)[96] = malloc((size_t)n * sizeof(*text));
	ret = -ENOMEM;
	if (x && labels && text) {
		for (int i = 0; i < n; i++) {
			x[i] = num(&rows[i], C_MEDIAN);
			y[i] = num(&rows[i], C_ERR_AVG);
			point_text(&rows[i], text[i], sizeof(text[i]));
			labels[i] = text[i];
		}
		struct mvod_plot_series s = {"configuration", x, y, n, MVOD_PLOT_POINTS,
					     (const char *const *)labels};
		struct mvod_plot_panel p = {"median frame time [ms], log scale", "err_avg", &s, 1, true};
		char path[4096], title[512];
		snprintf(path, sizeof(path), "%s/sweep.png", b->plots);
		snprintf(title, sizeof(title), "mvod bench %s: err_avg against frame time",
			 b->cfg.run.source);
		ret = plot_failed(path, mvod_plot_chart(path, title, &p, 1));
	}
	free(x);
	free(labels);
	free(text);
	return ret;
}

static int bench_sweep(const struct bench *b)
{
	const struct sweep *sw = b->sw;
	struct row *rows = calloc((size_t)sw->n, sizeof(*rows));
	int ret = rows ? 0 : -ENOMEM;
	if (ret)
		goto out;
	char tmp[] = "/tmp/mvod-bench-XXXXXX";
	int fd = mkstemp(tmp);
	if (fd < 0) {
		ret = -errno;
		LOG(ERROR, "cannot create a temporary file in /tmp: %s", strerror(errno));
		goto out;
	}
	close(fd);
	for (int i = 0; i < sw->n && !ret; i++)
		ret = sweep_one(b, &sw->cfg[i], tmp, i, sw->n, &rows[i]);
	unlink(tmp);
	if (ret)
		goto out;
	qsort(rows, (size_t)sw->n, sizeof(*rows), by_err_avg);
	ret = output_table(b, rows, sw->n);
	if (b->plots) {
		int pret = sweep_plot(b, rows, sw->n);
		ret = ret ? ret : pret;
	}
out:
	free(rows);
	return ret;
}

/*
 * --plots DIR: a folder (made at the end when it is not there yet) whose PNGs the output policy
 * takes; a file there was refused only after the whole run.
 */
static int check_plots(const char *dir)
{
	static const char *const names[] = {"path-top.png", "path-side.png", "errors.png",
					    "sweep.png"};
	struct stat st;
	if (stat(dir, &st) != 0)
		return cli_check_writable("--plots", dir);
	if (!S_ISDIR(st.st_mode)) {
		fprintf(stderr, "%s: --plots %s is no folder: name a folder for the PNGs\n", cli_prog,
			dir);
		return -ENOTDIR;
	}
	char path[4096];
	int ret = 0;
	for (size_t i = 0; i < sizeof(names) / sizeof(names[0]) && !ret; i++) {
		snprintf(path, sizeof(path), "%s/%s", dir, names[i]);
		ret = cli_check_writable("--plots", path);
	}
	return ret;
}

/*
 * Before any run, by the output policy: the tables and plots may not be the ground truth
 * (noted here, as sweep children read it, not this process), a directory or a disk.
 */
static int check_outputs(const struct bench *b)
{
	if (b->cfg.run.gt && mvod_input_note(b->cfg.run.gt) == -ENOMEM)
		return -ENOMEM;
	if (b->csv && cli_check_writable("--csv", b->csv))
		return -EINVAL;
	if (b->plots && check_plots(b->plots))
		return -EINVAL;
	return b->report && cli_check_writable("--report", b->report) ? -EINVAL : 0;
}

int mvod_cmd_bench(int argc, char **argv)
{
	struct bench b = {0};
	int ret = parse_cli(argc, argv, &b);
	if (ret == -ENOMEM)
		fprintf(stderr, "%s: out of memory\n", cli_prog);
	if (ret) {
		bench_free(&b);
		return ret > 0 ? 0 : ret == -ENOMEM ? EXIT_FAILURE : EXIT_USAGE;
	}
	cli_quiet_libraries();
	ret = check_outputs(&b);
	if (ret)
		ret = ret == -ENOMEM ? EXIT_FAILURE : EXIT_USAGE;
	else if (b.grid)
		ret = bench_sweep(&b) ? EXIT_FAILURE : EXIT_SUCCESS;
	else
		ret = bench_one(&b);
	bench_free(&b);
	return ret;
}
