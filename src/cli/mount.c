/* mvod mount: its command line, the camera file read and updated, and what it prints. */
#include "cli/cli.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mvod/log.h"
#include "mvod/mount.h"
#include "util/errbuf.h"
#include "util/output.h"
#include "util/read_file.h"

/* A camera file is small; mvod calibrate's with 500 views is about 200 kB. */
#define CAMERA_FILE_MAX_BYTES (4 * 1024 * 1024)

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "mount");
	fprintf(out,
"Measures how the camera sits above the floor from a calibration board lying flat on it:\n"
"the height of the camera centre above the floor and the camera's pitch and roll. Takes\n"
"the board's pose in every frame under the camera file's intrinsics, refuses views whose\n"
"pose is poor (corners off by over %g px, a board too small or too far for a pose within\n"
"%g %% of the height and %g deg, a board not flat, a view far from the others), averages\n"
"the rest, and writes the result into the camera file as its mount, which\n"
"mvod --scale height then uses when --camera-height is not given.\n"
"\n"
"  --source URI          the board on the floor, the camera still on its mount (required):\n"
"                        one image (images:DIR with one file), a short recording\n"
"                        (file:VIDEO), or a live camera (v4l2:, libcamera:), stopped with\n"
"                        Ctrl-C after a few seconds\n"
"  --board SPEC          the board (required), as for mvod calibrate:\n"
"                          charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT  (COLSxROWS squares)\n"
"                          chessboard:COLSxROWS:SQUARE_M             (inner corners)\n"
"  --calib FILE          the camera file (required): its intrinsics are used, and its\n"
"                        mount is written into it: mvod JSON (its \"mount\" block) or\n"
"                        OpenCV/ROS YAML or OpenCV XML (mount_height_m, mount_pitch_deg,\n"
"                        mount_roll_deg; the rest of the file kept); not KITTI calib.txt\n"
"                        (convert it with mvod calib-convert); replaced whole by temp+rename\n"
"  --board-thickness M   height of the board's printed face above the floor, metres\n"
"                        (0..0.1, default 0): added to the height\n"
"  --max-frames N        read at most N frames (default: the whole source)\n"
"  --dry-run             measure and print; write nothing\n"
"\n", MVOD_MOUNT_MAX_RMS_PX, 100 * MVOD_MOUNT_MAX_SD_REL, MVOD_MOUNT_MAX_SD_DEG);
	cli_usage_general(out);
	fprintf(out,
"The mount (camera frame: x right, y down, z forward; n the floor's normal, pointing down):\n"
"  height_m   distance from the camera centre to the floor plane, metres\n"
"  pitch_deg  asin(n_z): positive when the camera looks down\n"
"  roll_deg   atan2(n_x, n_y): positive when the camera is turned clockwise about its\n"
"             optical axis, seen from behind (the floor then leans towards +x)\n"
"\n"
"Example:\n"
"  mvod mount --source file:floor.mkv --board charuco:5x7:0.04:0.02:DICT_6X6_250 \\\n"
"       --calib calib.json\n"
"\n"
"Exit status: 0 on success, 1 on a runtime failure (no board, no good view, a camera file\n"
"that cannot be updated), 2 on a usage error.\n");
}

enum mount_opt_id {
	OPT_SOURCE = CLI_OPT_OWN, OPT_BOARD, OPT_CALIB, OPT_THICKNESS, OPT_MAX_FRAMES, OPT_DRY_RUN,
};

static const struct option own_opts[] = {
	{"source", required_argument, NULL, OPT_SOURCE},
	{"board", required_argument, NULL, OPT_BOARD},
	{"calib", required_argument, NULL, OPT_CALIB},
	{"board-thickness", required_argument, NULL, OPT_THICKNESS},
	{"max-frames", required_argument, NULL, OPT_MAX_FRAMES},
	{"dry-run", no_argument, NULL, OPT_DRY_RUN},
	{NULL, 0, NULL, 0},
};

struct cli {
	struct mvod_mount_opts o;
	const char *calib;
	int have_board, dry_run, quiet;
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	long v;
	int ret;
	switch (id) {
	case OPT_SOURCE: c->o.source = arg; return 0;
	case OPT_CALIB: c->calib = arg; return 0;
	case OPT_DRY_RUN: c->dry_run = 1; return 0;
	case OPT_BOARD:
		c->have_board = 1;
		return cli_parse_board(arg, &c->o.board);
	case OPT_THICKNESS:
		return cli_parse_double("board-thickness", arg, 0, 0.1, &c->o.thickness_m);
	case OPT_MAX_FRAMES:
		ret = cli_parse_int("max-frames", arg, 1, 1L << 40, &v);
		c->o.max_frames = v;
		return ret;
	}
	return -ENOENT;
}

static int parse_cli(int argc, char **argv, struct cli *c)
{
	int ret = cli_getopt(argc, argv, own_opts, parse_own, c, usage, NULL, &c->quiet);
	if (ret)
		return ret;
	const char *missing = !c->o.source ? "--source URI" : !c->have_board ? "--board SPEC"
							    : !c->calib ? "--calib FILE" : NULL;
	if (missing) {
		fprintf(stderr, "%s: %s is required%s; see %s --help\n", cli_prog, missing,
			c->calib || !c->o.source || !c->have_board
				? "" : " (the camera's intrinsics: make it with mvod calibrate)",
			cli_prog);
		return -EINVAL;
	}
	return 0;
}

/*
 * Whether an OpenCV/ROS camera file can take the mount (flow-style YAML cannot), tried on a
 * placeholder mount before any frame is read rather than after the measurement.
 */
static int check_editable(const char *path, const char *text, char *err, size_t errlen)
{
	const double placeholder[3] = {1, 0, 0};
	char *out = NULL, why[512];
	int ret = mvod_calib_filestorage_set_mount(text, placeholder, &out, why, sizeof(why));
	free(out);
	if (ret)
		mvod_errf(err, errlen, ret, "--calib %s: %s (or pass --dry-run to measure without "
			  "writing)", path, why);
	return ret;
}

/*
 * The camera file: its intrinsics and, unless --dry-run, its text, once it is known to be
 * mvod JSON that can be rewritten. Checked before any frame is read.
 */
static int open_camera(const struct cli *c, struct mvod_camera *cam, char **text)
{
	char err[1024];
	enum mvod_calib_format fmt;
	/* Before the file is read, which notes it as an input that no output may be. */
	if (!c->dry_run && cli_check_writable("--calib", c->calib))
		return -EACCES;
	int ret = mvod_calib_load_format(c->calib, cam, &fmt, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		return ret;
	}
	if (c->dry_run)
		return 0;
	if (fmt != MVOD_CALIB_FMT_MVOD && fmt != MVOD_CALIB_FMT_OPENCV && fmt != MVOD_CALIB_FMT_ROS) {
		LOG(ERROR, "--calib %s is %s, which has no place for a mount: convert it with mvod "
			   "calib-convert %s calib.json and pass --calib calib.json (or --dry-run "
			   "to measure without writing)", c->calib, mvod_calib_format_title(fmt),
		    c->calib);
		return -EINVAL;
	}
	if (access(c->calib, W_OK) != 0) {
		ret = -errno;
		LOG(ERROR, "--calib %s cannot be rewritten: %s: make it writable, or pass --dry-run "
			   "to measure without writing", c->calib, strerror(-ret));
		return ret;
	}
	ret = mvod_read_file(c->calib, CAMERA_FILE_MAX_BYTES, "camera file", 0, text, NULL, err,
			     sizeof(err));
	if (!ret && fmt != MVOD_CALIB_FMT_MVOD)
		ret = check_editable(c->calib, *text, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		free(*text); /* NULL when the read failed */
		*text = NULL;
	}
	return ret;
}

/* Writes the mount into the camera file, unless the file changed since it was read. */
static int update_camera(const struct cli *c, const char *text, const struct mvod_mount *m)
{
	char *now = NULL, err[1024];
	int ret = mvod_read_file(c->calib, CAMERA_FILE_MAX_BYTES, "camera file", 0, &now, NULL, err,
				 sizeof(err));
	if (!ret && strcmp(now, text) != 0)
		ret = mvod_errf(err, sizeof(err), -ESTALE, "%s changed while mvod mount ran: "
				"nothing written; run mvod mount again", c->calib);
	if (!ret) {
		mvod_input_release(c->calib);
		ret = mvod_mount_write(c->calib, text, m, err, sizeof(err));
	}
	if (ret)
		LOG(ERROR, "%s", err);
	free(now);
	return ret;
}

static void print_result(const struct cli *c, const struct mvod_mount_result *r)
{
	static const char *const why[] = {"", "off their pose", "too uncertain", "not flat",
					  "disagreeing"};
	int count[MVOD_MOUNT_DISAGREES + 1] = {0};
	for (int i = 0; i < r->n_views; i++)
		count[r->views[i].verdict]++;
	printf("%s: %lld frames read, the board in %d, %d views used", cli_prog,
	       (long long)r->frames_read, r->n_views, r->used);
	for (int k = MVOD_MOUNT_HIGH_ERROR; k <= MVOD_MOUNT_DISAGREES; k++)
		if (count[k])
			printf(", %d %s", count[k], why[k]);
	printf("\n%s: height %.4f m +- %.1f mm, pitch %.2f deg +- %.2f (positive: looking down), "
	       "roll %.2f deg +- %.2f\n", cli_prog, r->m.height_m, 1e3 * r->sd.height_m,
	       r->m.pitch_deg, r->sd.pitch_deg, r->m.roll_deg, r->sd.roll_deg);
	if (c->dry_run)
		printf("%s: --dry-run: %s not written\n", cli_prog, c->calib);
	else
		printf("%s: wrote the mount into %s\n", cli_prog, c->calib);
}

int mvod_cmd_mount(int argc, char **argv)
{
	struct cli c = {0};
	int ret = parse_cli(argc, argv, &c);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	cli_quiet_libraries();
	struct mvod_camera cam;
	char *text = NULL, err[1024];
	if (open_camera(&c, &cam, &text))
		return EXIT_FAILURE;
	/* A live camera never ends: the first Ctrl-C ends the recording and works on it. */
	c.o.stop = cli_stop_on_interrupt();
	struct mvod_mount_result res;
	ret = mvod_mount_measure(&c.o, &cam, &res, err, sizeof(err));
	if (ret)
		LOG(ERROR, "%s", err);
	else if (!c.dry_run)
		ret = update_camera(&c, text, &res.m);
	if (!ret && !c.quiet)
		print_result(&c, &res);
	mvod_mount_result_free(&res);
	free(text);
	return ret ? EXIT_FAILURE : EXIT_SUCCESS;
}
