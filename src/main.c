/* mvod: command line and the run loop's setup and teardown. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/capture.h"
#include "mvod/ipc.h"
#include "mvod/log.h"
#include "mvod/pipeline.h"

#define EXIT_USAGE 2

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
	(void)sig;
	stop_requested = 1;
}

static void usage(FILE *out)
{
	fprintf(out,
"Usage: mvod [run] --source URI [options]\n"
"Monocular visual odometry: frames in, camera poses out over LCM and to files.\n"
"\n"
"Input:\n"
"  --source URI          where frames come from (required):\n");
	for (int i = 0; mvod_source_backends[i]; i++)
		fprintf(out, "                          %-8s %s\n", mvod_source_backends[i]->scheme,
			mvod_source_backends[i]->summary);
	fprintf(out,
"  --calib FILE          camera calibration: mvod JSON (mvod-calibration/1) or KITTI\n"
"                        calib.txt; not needed for kitti: sources (they carry P0)\n"
"  --gt FILE             ground-truth trajectory, TUM or KITTI (matched by timestamp or\n"
"                        by index); enables the accuracy summary and the GT path in --plot\n"
"  --max-frames N        stop after N frames (default: the whole source)\n"
"\n"
"Visual odometry:\n"
"  --scale auto|gt       step length from triangulated structure (auto, default; the first\n"
"                        step defines the unit) or from the ground truth (gt: benchmarking)\n"
"  --features N          ORB feature cap (default 2000)\n"
"  --ratio R             Lowe's ratio test threshold, 1 = off (default 0.8)\n"
"  --no-cross-check      keep matches that are not mutual best matches\n"
"  --robust magsac|ransac  robust estimator of the essential matrix: MAGSAC++ (default)\n"
"                        or classic RANSAC\n"
"  --ransac-px P         inlier threshold in pixels (MAGSAC: its upper bound; default 1.0)\n"
"  --confidence C        RANSAC confidence (default 0.999)\n"
"  --min-parallax P      rotation-compensated median flow in pixels below which a frame is\n"
"                        treated as rotation only (default 1.0)\n"
"  --resize F            scale images by F in (0,1] before tracking (default 1)\n"
"  --blur K              Gaussian blur with a KxK kernel, K odd, 0 = off (default 0)\n"
"\n"
"Output:\n"
"  --lcm-url URL         LCM provider (default: $LCM_DEFAULT_URL, then LCM's default);\n"
"                        e.g. memq:// (in-process), file:///tmp/mvod.lcmlog?mode=w\n"
"  --no-lcm              do not publish over LCM\n"
"  --pose-channel NAME   LCM channel of mvod.pose_t (default MVOD_POSE)\n"
"  --status-channel NAME LCM channel of mvod.status_t (default MVOD_STATUS)\n"
"  --trajectory FILE     write every pose to FILE (complete lines only, even if killed)\n"
"  --format tum|kitti    trajectory format (default: kitti for *.kitti, else tum)\n"
"  --plot FILE.png       top-down plot of the path (with ground truth when --gt is given)\n"
"\n"
"General:\n"
"  --log-level LEVEL     error, warn, info (default) or debug\n"
"  -q, --quiet           same as --log-level warn, and no summary\n"
"  -h, --help            this text\n"
"  --version             print the version\n"
"\n"
"Example:\n"
"  mvod --source kitti:data/sequences/06 --gt data/poses/06.txt --scale gt \\\n"
"       --trajectory out.kitti --format kitti --plot out.png --lcm-url memq://\n"
"\n"
"Exit status: 0 on success, 1 on a runtime failure, 2 on a usage error.\n");
}

enum opt_id {
	OPT_SOURCE = 256, OPT_CALIB, OPT_GT, OPT_MAX_FRAMES, OPT_SCALE, OPT_FEATURES, OPT_RATIO,
	OPT_NO_CROSS, OPT_ROBUST, OPT_RANSAC_PX, OPT_CONFIDENCE, OPT_MIN_PARALLAX, OPT_RESIZE, OPT_BLUR,
	OPT_LCM_URL, OPT_NO_LCM, OPT_POSE_CH, OPT_STATUS_CH, OPT_TRAJ, OPT_FORMAT, OPT_PLOT,
	OPT_LOG_LEVEL, OPT_VERSION,
};

static const struct option long_opts[] = {
	{"source", required_argument, NULL, OPT_SOURCE},
	{"calib", required_argument, NULL, OPT_CALIB},
	{"gt", required_argument, NULL, OPT_GT},
	{"max-frames", required_argument, NULL, OPT_MAX_FRAMES},
	{"scale", required_argument, NULL, OPT_SCALE},
	{"features", required_argument, NULL, OPT_FEATURES},
	{"ratio", required_argument, NULL, OPT_RATIO},
	{"no-cross-check", no_argument, NULL, OPT_NO_CROSS},
	{"robust", required_argument, NULL, OPT_ROBUST},
	{"ransac-px", required_argument, NULL, OPT_RANSAC_PX},
	{"confidence", required_argument, NULL, OPT_CONFIDENCE},
	{"min-parallax", required_argument, NULL, OPT_MIN_PARALLAX},
	{"resize", required_argument, NULL, OPT_RESIZE},
	{"blur", required_argument, NULL, OPT_BLUR},
	{"lcm-url", required_argument, NULL, OPT_LCM_URL},
	{"no-lcm", no_argument, NULL, OPT_NO_LCM},
	{"pose-channel", required_argument, NULL, OPT_POSE_CH},
	{"status-channel", required_argument, NULL, OPT_STATUS_CH},
	{"trajectory", required_argument, NULL, OPT_TRAJ},
	{"format", required_argument, NULL, OPT_FORMAT},
	{"plot", required_argument, NULL, OPT_PLOT},
	{"log-level", required_argument, NULL, OPT_LOG_LEVEL},
	{"quiet", no_argument, NULL, 'q'},
	{"help", no_argument, NULL, 'h'},
	{"version", no_argument, NULL, OPT_VERSION},
	{NULL, 0, NULL, 0},
};

struct cli {
	struct mvod_run_opts run;
	const char *lcm_url, *pose_ch, *status_ch;
	int no_lcm, quiet, format_given;
};

static int bad_value(const char *opt, const char *val, const char *want)
{
	fprintf(stderr, "mvod: --%s %s: expected %s\n", opt, val, want);
	return -EINVAL;
}

static int parse_double(const char *opt, const char *s, double lo, double hi, double *out)
{
	char *end;
	errno = 0;
	double v = strtod(s, &end);
	if (errno || end == s || *end || !isfinite(v) || v < lo || v > hi) {
		char want[96];
		snprintf(want, sizeof(want), "a number in [%g, %g]", lo, hi);
		return bad_value(opt, s, want);
	}
	*out = v;
	return 0;
}

static int parse_int(const char *opt, const char *s, long lo, long hi, long *out)
{
	char *end;
	errno = 0;
	long v = strtol(s, &end, 10);
	if (errno || end == s || *end || v < lo || v > hi) {
		char want[96];
		snprintf(want, sizeof(want), "an integer in [%ld, %ld]", lo, hi);
		return bad_value(opt, s, want);
	}
	*out = v;
	return 0;
}

static int parse_vo_option(int id, const char *arg, struct mvod_vo_params *vo)
{
	long v = 0;
	int ret = 0;
	switch (id) {
	case OPT_SCALE:
		if (strcmp(arg, "auto") == 0)
			vo->scale_mode = MVOD_SCALE_MODE_AUTO;
		else if (strcmp(arg, "gt") == 0)
			vo->scale_mode = MVOD_SCALE_MODE_GT;
		else
			ret = bad_value("scale", arg, "auto or gt");
		return ret;
	case OPT_FEATURES:
		ret = parse_int("features", arg, 50, 100000, &v);
		vo->max_features = (int)v;
		return ret;
	case OPT_RATIO:
		return parse_double("ratio", arg, 0.1, 1.0, &vo->ratio);
	case OPT_NO_CROSS:
		vo->cross_check = false;
		return 0;
	case OPT_ROBUST:
		return mvod_robust_method_parse(arg, &vo->robust) ? bad_value("robust", arg, "magsac or ransac")
								  : 0;
	case OPT_RANSAC_PX:
		return parse_double("ransac-px", arg, 0.05, 50, &vo->ransac_px);
	case OPT_CONFIDENCE:
		return parse_double("confidence", arg, 0.5, 0.999999, &vo->ransac_conf);
	case OPT_MIN_PARALLAX:
		return parse_double("min-parallax", arg, 0, 100, &vo->min_parallax_px);
	case OPT_RESIZE:
		return parse_double("resize", arg, 0.05, 1, &vo->resize);
	case OPT_BLUR:
		ret = parse_int("blur", arg, 0, 99, &v);
		if (!ret && v != 0 && v % 2 == 0)
			ret = bad_value("blur", arg, "an odd kernel size, or 0");
		vo->blur_ksize = (int)v;
		return ret;
	}
	return -ENOENT;
}

static int parse_option(int id, const char *arg, struct cli *c)
{
	struct mvod_run_opts *r = &c->run;
	long v;
	switch (id) {
	case OPT_SOURCE: r->source = arg; return 0;
	case OPT_CALIB: r->calib = arg; return 0;
	case OPT_GT: r->gt = arg; return 0;
	case OPT_MAX_FRAMES:
		if (parse_int("max-frames", arg, 1, 1L << 40, &v))
			return -EINVAL;
		r->max_frames = v;
		return 0;
	case OPT_LCM_URL: c->lcm_url = arg; return 0;
	case OPT_NO_LCM: c->no_lcm = 1; return 0;
	case OPT_POSE_CH: c->pose_ch = arg; return 0;
	case OPT_STATUS_CH: c->status_ch = arg; return 0;
	case OPT_TRAJ: r->trajectory = arg; return 0;
	case OPT_FORMAT:
		c->format_given = 1;
		return mvod_traj_format_parse(arg, &r->traj_format) ? bad_value("format", arg, "tum or kitti")
								    : 0;
	case OPT_PLOT: r->plot = arg; return 0;
	case OPT_LOG_LEVEL: {
		enum mvod_log_level lvl;
		if (mvod_log_parse_level(arg, &lvl))
			return bad_value("log-level", arg, "error, warn, info or debug");
		mvod_log_set_level(lvl);
		return 0;
	}
	case 'q':
		c->quiet = 1;
		mvod_log_set_level(MVOD_LOG_WARN);
		return 0;
	}
	return parse_vo_option(id, arg, &r->vo);
}

static bool has_suffix(const char *s, const char *suffix)
{
	size_t n = strlen(s), m = strlen(suffix);
	return n >= m && strcmp(s + n - m, suffix) == 0;
}

/* 0 to run, 1 when help/version was printed, -EINVAL on a usage error. */
static int parse_cli(int argc, char **argv, struct cli *c)
{
	mvod_run_opts_default(&c->run);
	int id;
	opterr = 0;
	while ((id = getopt_long(argc, argv, "qh", long_opts, NULL)) != -1) {
		if (id == 'h') {
			usage(stdout);
			return 1;
		}
		if (id == OPT_VERSION) {
			printf("mvod %s\n", MVOD_VERSION);
			return 1;
		}
		if (id == '?') {
			fprintf(stderr, "mvod: unknown or incomplete option '%s'; see mvod --help\n",
				argv[optind - 1]);
			return -EINVAL;
		}
		if (parse_option(id, optarg, c))
			return -EINVAL;
	}
	if (optind < argc && strcmp(argv[optind], "run") == 0)
		optind++;
	if (optind < argc) {
		fprintf(stderr, "mvod: unexpected argument '%s'; see mvod --help\n", argv[optind]);
		return -EINVAL;
	}
	if (!c->run.source) {
		fprintf(stderr, "mvod: --source URI is required, e.g. --source file:video.mkv; "
				"see mvod --help\n");
		return -EINVAL;
	}
	if (!c->format_given && c->run.trajectory && has_suffix(c->run.trajectory, ".kitti"))
		c->run.traj_format = MVOD_TRAJ_KITTI;
	return 0;
}

static void print_summary(const struct cli *c, const struct mvod_run_summary *s)
{
	printf("mvod: %lld frames in %.2f s (%.1f fps), %lld tracked, %lld held\n",
	       (long long)s->frames, s->wall_s, s->fps, (long long)s->tracked, (long long)s->held);
	printf("mvod: ms per frame, mean (max):");
	for (int k = 0; k < MVOD_STAGE_COUNT; k++)
		printf(" %s %.2f (%.1f)", mvod_stage_names[k], s->stage_ms_mean[k], s->stage_ms_max[k]);
	printf("\n");
	if (!s->have_gt)
		return;
	printf("mvod: accuracy vs ground truth: rotation error %.3f deg/frame (max %.3f), "
	       "direction error %.2f deg/frame (max %.2f), err_avg %.3f (max %.3f), ",
	       s->rpe.rot_deg_mean, s->rpe.rot_deg_max, s->rpe.dir_deg_mean, s->rpe.dir_deg_max,
	       s->rpe.err_avg, s->rpe.err_max);
	if (isnan(s->ate_rmse_m))
		printf("ATE n/a (the ground truth does not move)\n");
	else
		printf("ATE %.3f m over %.1f m, %.1f %% (%s)\n", s->ate_rmse_m, s->path_len_m,
		       100.0 * s->ate_rmse_m / fmax(s->path_len_m, 1e-9),
		       c->run.vo.scale_mode == MVOD_SCALE_MODE_GT ? "SE(3)-aligned" : "Sim(3)-aligned");
}

/*
 * FFmpeg prints its own diagnostics for a corrupt file before mvod can say which file and what
 * to do; keep them for --log-level debug. A value the user exported wins.
 */
static void quiet_ffmpeg(void)
{
	if (mvod_log_get_level() < MVOD_LOG_DEBUG)
		setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0); /* AV_LOG_QUIET */
}

int main(int argc, char **argv)
{
	struct cli c = {0};
	int ret = parse_cli(argc, argv, &c);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	quiet_ffmpeg();
	struct sigaction sa = {.sa_handler = on_signal};
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	struct mvod_ipc *ipc = NULL;
	if (!c.no_lcm) {
		ret = mvod_ipc_create(c.lcm_url, c.pose_ch, c.status_ch, &ipc);
		if (ret) {
			LOG(ERROR, "cannot open LCM at %s: check --lcm-url (e.g. memq://, "
				   "udpm://239.255.76.67:7667?ttl=0, file:///tmp/log?mode=w)",
			    c.lcm_url ? c.lcm_url : "the default URL");
			return EXIT_FAILURE;
		}
	}
	struct mvod_run_summary sum;
	ret = mvod_run(&c.run, ipc, &stop_requested, &sum);
	mvod_ipc_destroy(ipc);
	if (!c.quiet && !ret)
		print_summary(&c, &sum);
	return ret ? EXIT_FAILURE : EXIT_SUCCESS;
}
