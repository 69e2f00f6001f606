/* mvod calibrate: its command line, the up-front checks, and what it prints. */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/calibrate.h"
#include "mvod/log.h"
#include "util/output.h"

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "calibrate");
	fprintf(out,
"Finds a calibration board in every frame of a recording, picks the views that best cover\n"
"the image and the range of board tilts, calibrates the camera, drops views whose error is\n"
"far above the rest and calibrates again, and writes mvod JSON (mvod-calibration/1).\n"
"\n"
"  --source URI          frames to read (required): file:VIDEO, images:DIR, or a live\n"
"                        camera (v4l2:/dev/video0, libcamera:0; see mvod --list-cameras):\n"
"                        press Ctrl-C when enough views are recorded, and mvod calibrates\n"
"                        on them (a second Ctrl-C aborts)\n"
"  --board SPEC          the target (required); make one with mvod board:\n"
"                          charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT  (COLSxROWS squares)\n"
"                          chessboard:COLSxROWS:SQUARE_M             (inner corners)\n"
"                        SQUARE_M is the side of a printed square in metres, as measured\n"
"  --out FILE            calibration to write (required); replaced only on success, and\n"
"                        not when Ctrl-C stops a recorded file before its end\n"
"  --model pinhole|fisheye  pinhole-radtan k1 k2 p1 p2 k3 (default) or Kannala-Brandt\n"
"                        fisheye k1..k4 (lenses over about 120 deg)\n"
"  --rational            pinhole with 8 coefficients k1 k2 p1 p2 k3 k4 k5 k6 (wide lenses)\n"
"  --max-views N         views to calibrate with, 10..500 (default 80)\n"
"  --min-corners N       corners a view needs (default: all of a chessboard, 6 of ChArUco)\n"
"  --max-frames N        read at most N frames (default: the whole source)\n"
"  --report FILE.png     picture of the corner coverage, the error per view, and a frame\n"
"                        before and after undistortion\n"
"  --force               write the calibration and exit 0 whatever the verdict (see below)\n"
"\n");
	cli_usage_general(out);
	fprintf(out,
"The JSON holds model, image_size, K, distortion, rms_px, std_dev (pinhole), verdict,\n"
"board, source, created (UTC), views_used and per view its rms_px, rvec and tvec (board to\n"
"camera, metres).\n"
"The verdict is good, poor coverage, too few views, high error or not one camera, with what\n"
"to do about it. Not one camera (another image size, or two halves of the views that disagree)\n"
"is a blend of cameras: the file is not written, unless --force. Too few views (under 15) is\n"
"written, and exits 1. mvod run warns at start when --calib records a verdict but good.\n"
"\n"
"Example:\n"
"  mvod calibrate --source file:board.mkv --board charuco:5x7:0.04:0.02:DICT_6X6_250 \\\n"
"       --out calib.json --report calib.png\n"
"\n"
"Exit status: 0 on success, 1 on a run-time fault (no board, too few views, not one camera,\n"
"a write that failed; --force makes the last two verdicts 0), 2 on a usage error (--out or\n"
"--report refused at start too).\n");
}

enum calib_opt_id {
	OPT_SOURCE = CLI_OPT_OWN, OPT_BOARD, OPT_OUT, OPT_MODEL, OPT_RATIONAL, OPT_MAX_VIEWS,
	OPT_MIN_CORNERS, OPT_MAX_FRAMES, OPT_REPORT, OPT_FORCE,
};

static const struct option own_opts[] = {
	{"source", required_argument, NULL, OPT_SOURCE},
	{"board", required_argument, NULL, OPT_BOARD},
	{"out", required_argument, NULL, OPT_OUT},
	{"model", required_argument, NULL, OPT_MODEL},
	{"rational", no_argument, NULL, OPT_RATIONAL},
	{"max-views", required_argument, NULL, OPT_MAX_VIEWS},
	{"min-corners", required_argument, NULL, OPT_MIN_CORNERS},
	{"max-frames", required_argument, NULL, OPT_MAX_FRAMES},
	{"report", required_argument, NULL, OPT_REPORT},
	{"force", no_argument, NULL, OPT_FORCE},
	{NULL, 0, NULL, 0},
};

struct cli {
	struct mvod_calib_opts o;
	const char *out;
	int have_board, quiet;
	bool force;   /* --force: any verdict is written and exits 0 */
	bool refused; /* an output the policy refused: a usage error */
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	long v;
	int ret = 0;
	switch (id) {
	case OPT_SOURCE: c->o.source = arg; return 0;
	case OPT_OUT: c->out = arg; return 0;
	case OPT_REPORT: c->o.report = arg; return 0;
	case OPT_RATIONAL: c->o.rational = true; return 0;
	case OPT_FORCE: c->force = true; return 0;
	case OPT_BOARD:
		c->have_board = 1;
		return cli_parse_board(arg, &c->o.board);
	case OPT_MODEL:
		if (strcmp(arg, "pinhole") == 0)
			c->o.model = MVOD_CAM_PINHOLE_RADTAN;
		else if (strcmp(arg, "fisheye") == 0)
			c->o.model = MVOD_CAM_FISHEYE_KB4;
		else
			ret = cli_bad_value("model", arg, "pinhole or fisheye");
		return ret;
	case OPT_MAX_VIEWS:
		ret = cli_parse_int("max-views", arg, 10, 500, &v);
		c->o.max_views = (int)v;
		return ret;
	case OPT_MIN_CORNERS:
		ret = cli_parse_int("min-corners", arg, 4, 10000, &v);
		c->o.min_corners = (int)v;
		return ret;
	case OPT_MAX_FRAMES:
		ret = cli_parse_int("max-frames", arg, 1, 1L << 40, &v);
		c->o.max_frames = v;
		return ret;
	}
	return -ENOENT;
}

static int parse_cli(int argc, char **argv, struct cli *c)
{
	mvod_calib_opts_default(&c->o);
	int ret = cli_getopt(argc, argv, own_opts, parse_own, c, usage, NULL, &c->quiet);
	if (ret)
		return ret;
	const char *missing = !c->o.source ? "--source URI" : !c->have_board ? "--board SPEC"
							    : !c->out ? "--out FILE" : NULL;
	if (missing) {
		fprintf(stderr, "%s: %s is required; see %s --help\n", cli_prog, missing, cli_prog);
		return -EINVAL;
	}
	if (c->o.rational && c->o.model == MVOD_CAM_FISHEYE_KB4) {
		fprintf(stderr, "%s: --rational is for the pinhole model; the fisheye model has "
				"k1..k4\n", cli_prog);
		return -EINVAL;
	}
	return 0;
}

static void print_params(const struct mvod_calib_result *r)
{
	static const char *const pinhole[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"};
	static const char *const fisheye[] = {"k1", "k2", "k3", "k4"};
	const char *const *names = r->cam.model == MVOD_CAM_FISHEYE_KB4 ? fisheye : pinhole;
	const double K[4] = {r->cam.fx, r->cam.fy, r->cam.cx, r->cam.cy};
	static const char *const knames[] = {"fx", "fy", "cx", "cy"};
	for (int i = 0; i < 4; i++) {
		printf("  %-3s %10.3f px", knames[i], K[i]);
		if (r->has_std)
			printf("  +- %.3f", r->std_K[i]);
		printf("\n");
	}
	for (int i = 0; i < r->cam.n_dist; i++) {
		printf("  %-3s %10.5f", names[i], r->cam.dist[i]);
		if (r->has_std)
			printf("     +- %.5f", r->std_dist[i]);
		printf("\n");
	}
}

static void print_result(const struct cli *c, const struct mvod_calib_result *r)
{
	printf("%s: %lld frames read", cli_prog, (long long)r->frames_read);
	if (r->frames_repeated)
		printf(" (%lld skipped: a still picture)", (long long)r->frames_repeated);
	printf(", %lld with the board, %d views selected, %d used", (long long)r->frames_with_board,
	       r->views_selected, r->views_used);
	if (r->views_used < r->views_selected)
		printf(" (%d above %.3f px dropped)", r->views_selected - r->views_used, r->outlier_px);
	printf("\n%s: %.1f s reading and detecting, %.1f s selecting and calibrating\n", cli_prog,
	       r->read_s, r->solve_s);
	printf("%s: RMS reprojection error %.3f px, model %s%s\n", cli_prog, r->rms_px,
	       mvod_cam_model_name(r->cam.model),
	       r->has_std ? " (+- one standard deviation)" : "");
	print_params(r);
	printf("%s: verdict: %s. %s\n", cli_prog, mvod_calib_verdict_name(r->verdict), r->advice);
}

/*
 * What the verdict lets calibrate do, as --help says: a blend of cameras ("not one camera") is
 * not written, and too few views is written but exits 1, each unless --force. Returns the exit
 * status; *write: whether to write the file.
 */
static int judge(const struct cli *c, const struct mvod_calib_result *r, bool *write)
{
	*write = c->force || r->verdict != MVOD_VERDICT_MIXED;
	if (c->force || (r->verdict != MVOD_VERDICT_MIXED && r->verdict != MVOD_VERDICT_FEW_VIEWS))
		return EXIT_SUCCESS;
	if (!*write)
		LOG(ERROR, "%s not written: the views are not one camera (the verdict above): "
			   "calibrate each camera on its own frames, or pass --force to write the "
			   "blend anyway", c->out);
	return EXIT_FAILURE;
}

/*
 * --out and --report by the output policy once the source is open and its files are noted as
 * inputs (an --out naming a frame is refused), before a frame is read: found out now, not
 * after an hour of video.
 */
static int check_outputs(void *ctx, char *err, size_t errlen)
{
	struct cli *c = ctx;
	char target[4096];
	int ret = mvod_output_check("--out", c->out, target, sizeof(target), NULL, err, errlen);
	if (!ret && c->o.report)
		ret = mvod_output_check("--report", c->o.report, target, sizeof(target), NULL, err,
					errlen);
	c->refused = ret != 0;
	return ret;
}

int mvod_cmd_calibrate(int argc, char **argv)
{
	struct cli c = {0};
	int ret = parse_cli(argc, argv, &c);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	cli_quiet_libraries();
	/* A folder or a folder that cannot be written in: refused before the source opens too. */
	if (cli_check_writable("--out", c.out) || (c.o.report && cli_check_writable("--report", c.o.report)))
		return EXIT_USAGE;
	c.o.check_outputs = check_outputs;
	c.o.check_ctx = &c;
	/* A live camera never ends: the first Ctrl-C ends the recording and works on it. */
	c.o.stop = cli_stop_on_interrupt();
	struct mvod_calib_result res;
	char err[MVOD_ERR_MAX];
	ret = mvod_calibrate(&c.o, &res, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		mvod_calib_result_free(&res);
		return c.refused ? EXIT_USAGE : EXIT_FAILURE;
	}
	if (!c.quiet)
		print_result(&c, &res);
	bool write;
	int status = judge(&c, &res, &write);
	struct mvod_calib_meta meta;
	mvod_calib_result_meta(&res, &c.o, &meta);
	ret = write ? mvod_calib_save(c.out, &res.cam, &meta) : 0;
	if (ret)
		LOG(ERROR, "cannot write %s: %s", c.out, strerror(-ret));
	else if (write && !c.quiet)
		printf("%s: wrote %s%s%s\n", cli_prog, c.out, c.o.report ? " and " : "",
		       c.o.report ? c.o.report : "");
	if (!ret && write && status)
		LOG(ERROR, "%s: too few views to trust it (exit status 1): record more, or pass "
			   "--force to accept it", c.out);
	mvod_calib_result_free(&res);
	return ret ? EXIT_FAILURE : status;
}
