/* Option parsing shared by the subcommands. */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mvod/board.h"
#include "mvod/capture.h"
#include "mvod/log.h"
#include "mvod/pipeline.h"
#include "util/output.h"

const char *cli_prog = "mvod";

/* Every subcommand; with the [log] keys of the config table. */
static const struct option general_opts[] = {
	{"help", no_argument, NULL, 'h'},
	{"version", no_argument, NULL, CLI_OPT_VERSION},
	{NULL, 0, NULL, 0},
};

static int append(struct option *dst, int n, const struct option *src)
{
	for (const struct option *o = src; o && o->name && n < CLI_MAX_OPTIONS - 1; o++)
		dst[n++] = *o;
	return n;
}

static bool is_general_key(const struct mvod_config_key *k)
{
	return strcmp(k->section, "log") == 0;
}

void cli_options_join(struct option *dst, bool with_run, const struct option *own)
{
	int n = append(dst, 0, general_opts);
	for (int k = 0; k < mvod_config_nkeys && n < CLI_MAX_OPTIONS - 1; k++) {
		const struct mvod_config_key *key = &mvod_config_keys[k];
		if (with_run || is_general_key(key))
			dst[n++] = (struct option){key->flag,
						   key->type == MVOD_CONFIG_BOOL ? no_argument
										 : required_argument,
						   NULL, CLI_OPT_KEY + k};
	}
	n = append(dst, n, own);
	dst[n] = (struct option){0};
}

int cli_bad_value(const char *opt, const char *val, const char *want)
{
	fprintf(stderr, "%s: --%s %s: expected %s\n", cli_prog, opt, val, want);
	return -EINVAL;
}

int cli_parse_double(const char *opt, const char *s, double lo, double hi, double *out)
{
	char *end;
	errno = 0;
	double v = strtod(s, &end);
	if (errno || end == s || *end || !isfinite(v) || v < lo || v > hi) {
		char want[96];
		snprintf(want, sizeof(want), "a number in [%g, %g]", lo, hi);
		return cli_bad_value(opt, s, want);
	}
	*out = v;
	return 0;
}

int cli_parse_int(const char *opt, const char *s, long lo, long hi, long *out)
{
	char *end;
	errno = 0;
	long v = strtol(s, &end, 10);
	if (errno || end == s || *end || v < lo || v > hi) {
		char want[96];
		snprintf(want, sizeof(want), "an integer in [%ld, %ld]", lo, hi);
		return cli_bad_value(opt, s, want);
	}
	*out = v;
	return 0;
}

bool cli_has_suffix(const char *s, const char *suffix)
{
	size_t n = strlen(s), m = strlen(suffix);
	return n >= m && strcmp(s + n - m, suffix) == 0;
}

int cli_parse_board(const char *s, struct mvod_board *b)
{
	char why[256];
	if (mvod_board_parse(s, b, why, sizeof(why)) == 0)
		return 0;
	fprintf(stderr, "%s: --board %s: %s\n", cli_prog, s, why);
	return -EINVAL;
}

int cli_check_writable(const char *opt, const char *path)
{
	char target[4096], err[MVOD_ERR_MAX];
	int ret = mvod_output_check(opt, path, target, sizeof(target), NULL, err, sizeof(err));
	if (ret)
		fprintf(stderr, "%s: %s\n", cli_prog, err);
	return ret;
}

int cli_run_status(int ret, const struct mvod_run_summary *s)
{
	if (!ret)
		return EXIT_SUCCESS;
	/* An unknown scheme is the URI's fault, as everything the run found before a frame. */
	return s->config_failed || ret == -EPROTONOSUPPORT ? EXIT_USAGE : EXIT_FAILURE;
}

void cli_usage_input(FILE *out)
{
	fprintf(out,
"Input:\n"
"  --source URI          where frames come from (required):\n");
	for (int i = 0; mvod_source_backends[i]; i++)
		fprintf(out, "                          %-8s %s\n", mvod_source_backends[i]->scheme,
			mvod_source_backends[i]->summary);
	fprintf(out,
"  --calib FILE          camera calibration: mvod JSON (mvod-calibration/1), OpenCV\n"
"                        YAML/XML, ROS camera_info, JSON [K, dist], KITTI calib.txt or DSO\n"
"                        camera.txt (see mvod calib-convert --help); not needed for kitti:,\n"
"                        kitti-raw: and euroc: sources, nor tum: freiburg1/2/3 and monoVO\n"
"                        folders\n"
"  --gt FILE             ground-truth trajectory, TUM or KITTI (matched by timestamp or\n"
"                        by index); enables the accuracy summary and the GT path in --plot.\n"
"                        Default: the dataset's own (kitti: ../../poses/NN.txt, kitti-raw:\n"
"                        oxts/data/, euroc:, tum: groundtruth.txt), as camera poses in the\n"
"                        first frame's camera frame\n"
"  --max-frames N        stop after N frames (default: the whole source)\n"
"\n");
}

/* The run's files, which mvod run and a single mvod bench run both write. */
void cli_usage_files(FILE *out)
{
	fprintf(out,
"  --trajectory FILE     write every pose to FILE (complete lines only, even if killed)\n"
"  --format tum|kitti    trajectory format (default: kitti for *.kitti, else tum)\n"
"  --plot FILE.png       top-down plot of the path (with ground truth when --gt is given)\n");
}

void cli_usage_vo(FILE *out)
{
	fprintf(out,
"Visual odometry:\n"
"  --mode map|twoview    map (default): a local map of keyframes and points that carries\n"
"                        one scale, PnP per frame and windowed bundle adjustment; twoview:\n"
"                        frame to frame, each step scaled by the structure it shares with\n"
"                        the last (kept for comparison; --detector sift needs it)\n"
"  --ba-sync             map mode, live camera: wait for each bundle adjustment (on its own\n"
"                        thread) at the frame after its keyframe, as files and datasets\n"
"                        always do: results independent of the machine's speed\n"
"  --scale MODE          step length: auto (default) from triangulated structure, the first\n"
"                        step defines the unit; gt from the ground truth (benchmarking);\n"
"                        height: metres from the ground plane and --camera-height;\n"
"                        external: metres from the robot's speed (mvod.speed_t; map mode:\n"
"                        the map rescaled by the distance it reports at keyframes)\n"
"  --camera-height M     the camera's height above the ground in metres, up to 20\n"
"                        (--scale height; 0 = none: the --calib file's mount, if it\n"
"                        has one; see mvod mount --help)\n"
"  --speed-channel NAME  LCM channel of mvod.speed_t (default MVOD_SPEED)\n"
"  --speed-url URL       where speed comes from: an LCM URL, or file://LOG?mode=r to read\n"
"                        a log (matched to frames by utime); default: the --lcm-url\n"
"  --frontend auto|klt|orb  klt: FAST corners tracked frame to frame by pyramidal\n"
"                        Lucas-Kanade (--tracks caps them); orb: features matched by\n"
"                        descriptor in every frame (--detector, --matcher, --ratio, --best\n"
"                        below apply to it alone, and klt refuses them; --features is its\n"
"                        count); auto (default): klt, but orb when one of those four\n"
"                        options is given a value other than its default\n"
"  --detector orb|sift   keypoints and descriptors: ORB (default; binary, fast) or SIFT\n"
"  --matcher M           how features of consecutive frames are paired (default bf):\n"
"                          bf          brute force, ratio test and cross-check\n"
"                          bf-cross    brute force, mutual nearest neighbours, the --best N\n"
"                                      closest\n"
"                          bf-ratio    brute force, ratio test only\n"
"                          flann       FLANN nearest neighbour, unfiltered (LSH 6/12/1 for\n"
"                                      ORB, 5 kd-trees for SIFT)\n"
"                          flann-ratio FLANN with the ratio test\n"
"  --features N          feature count of orb and sift (default 2000); picks no front\n"
"                        end: klt's is --tracks\n"
"  --tracks N            track cap of the klt front end (default 500; orb refuses it)\n"
"  --ratio R             Lowe's ratio test threshold, 1 = off (default 0.8)\n"
"  --best N              matches kept by bf-cross, 0 = all (default 200)\n"
"  --robust magsac|ransac  robust estimator of the essential matrix: MAGSAC++ (default)\n"
"                        or classic RANSAC\n"
"  --ransac-px P         inlier threshold in pixels (MAGSAC: its upper bound; default 1.0)\n"
"  --confidence C        RANSAC confidence (default 0.999)\n"
"  --min-parallax P      rotation-compensated median flow in pixels below which a frame is\n"
"                        treated as rotation only (default 1.0; KLT tracks use half)\n"
"  --resize F            scale images by F in (0,1] before tracking (default 1)\n"
"  --blur K              Gaussian blur with a KxK kernel, K odd, 0 = off (default 0)\n"
"\n");
}

void cli_usage_general(FILE *out)
{
	fprintf(out,
"General:\n"
"  --log-level LEVEL     error, warn, info (default) or debug\n"
"  -q, --quiet           same as --log-level warn, and no summary\n"
"  -h, --help            this text\n"
"  --version             print the version\n"
"\n");
}

int cli_check_frontend(const struct mvod_config *cfg)
{
	char err[256];
	if (!mvod_config_check_frontend(&cfg->run.vo, err, sizeof(err)))
		return 0;
	fprintf(stderr, "%s: %s; see %s --help\n", cli_prog, err, cli_prog);
	return -EINVAL;
}

int cli_parse_key(int k, const char *arg, struct mvod_config *cfg)
{
	char want[256];
	if (mvod_config_set(cfg, k, arg, want, sizeof(want)) == 0)
		return 0;
	return cli_bad_value(mvod_config_keys[k].flag, arg, want);
}

/* Short options are the table's short flags (-q); getopt hands back the letter. */
static int short_key(int id)
{
	for (int k = 0; k < mvod_config_nkeys; k++)
		if (mvod_config_keys[k].short_flag && mvod_config_keys[k].short_flag == id)
			return k;
	return -1;
}

static int parse_option(int id, const char *arg, cli_own_parse_fn own_parse, void *ctx,
			struct mvod_config *cfg)
{
	if (id >= CLI_OPT_OWN && own_parse)
		return own_parse(id, arg, ctx);
	int k = id >= CLI_OPT_KEY && id < CLI_OPT_KEY + mvod_config_nkeys ? id - CLI_OPT_KEY
									    : short_key(id);
	return k >= 0 ? cli_parse_key(k, arg, cfg) : -ENOENT;
}

int cli_getopt_args(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
		    void *ctx, void (*usage)(FILE *), struct mvod_config *cfg, int *quiet,
		    const char **args, int nargs, const char *args_usage)
{
	struct option opts[CLI_MAX_OPTIONS];
	cli_options_join(opts, cfg != NULL, own);
	struct mvod_config general;
	mvod_config_default(&general);
	struct mvod_config *c = cfg ? cfg : &general;
	int id;
	opterr = 0;
	optind = 1;
	while ((id = getopt_long(argc, argv, "qh", opts, NULL)) != -1) {
		if (id == 'h') {
			usage(stdout);
			return 1;
		}
		if (id == CLI_OPT_VERSION) {
			printf("mvod %s\n", MVOD_VERSION);
			return 1;
		}
		if (id == '?') {
			fprintf(stderr, "%s: unknown or incomplete option '%s'; see %s --help\n",
				cli_prog, argv[optind - 1], cli_prog);
			return -EINVAL;
		}
		int ret = parse_option(id, optarg, own_parse, ctx, c);
		if (ret == -ENOENT) {
			fprintf(stderr, "%s: option '%s' does not apply here; see %s --help\n",
				cli_prog, argv[optind - 1], cli_prog);
			return -EINVAL;
		}
		if (ret)
			return -EINVAL;
	}
	/* GNU getopt has moved the operands behind the options, wherever the user put them. */
	if (argc - optind != nargs) {
		if (nargs)
			fprintf(stderr, "%s: expected %s; see %s --help\n", cli_prog, args_usage,
				cli_prog);
		else
			fprintf(stderr, "%s: unexpected argument '%s'; see %s --help\n", cli_prog,
				argv[optind], cli_prog);
		return -EINVAL;
	}
	for (int i = 0; i < nargs; i++)
		args[i] = argv[optind + i];
	if (!cfg)
		mvod_config_apply_log(&general);
	if (quiet)
		*quiet = c->quiet;
	return 0;
}

int cli_getopt(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
	       void *ctx, void (*usage)(FILE *), struct mvod_config *cfg, int *quiet)
{
	return cli_getopt_args(argc, argv, own, own_parse, ctx, usage, cfg, quiet, NULL, 0, NULL);
}

/*
 * FFmpeg and libcamera print their own diagnostics (a corrupt file, every camera probed) before
 * mvod can say which source and what to do; keep them for --log-level debug. A value the user
 * exported wins.
 */
void cli_quiet_libraries(void)
{
	if (mvod_log_get_level() >= MVOD_LOG_DEBUG)
		return;
	setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0); /* AV_LOG_QUIET */
	setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
}

static volatile sig_atomic_t stop_reading;

static void on_stop(int sig)
{
	(void)sig;
	stop_reading = 1;
}

volatile sig_atomic_t *cli_stop_on_interrupt(void)
{
	struct sigaction sa = {.sa_handler = on_stop, .sa_flags = SA_RESETHAND};
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	return &stop_reading;
}
