/* mvod run: its command line and the run loop's setup and teardown. */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/capture.h"
#include "mvod/ipc.h"
#include "mvod/log.h"
#include "mvod/pipeline.h"

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
"       mvod --list-cameras\n"
"       mvod calibrate|board|calib-convert|bench|view ...   (mvod COMMAND --help)\n"
"Monocular visual odometry: frames in, camera poses out over LCM and to files.\n"
"\n");
	cli_usage_input(out);
	cli_usage_vo(out);
	fprintf(out,
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
"Cameras:\n"
"  --list-cameras        list the V4L2 and libcamera cameras attached, their formats, sizes\n"
"                        and rates, each with the --source URI that opens it; then exit\n"
"\n");
	cli_usage_general(out);
	fprintf(out,
"Commands:\n"
"  run                   track a source and publish poses (the default)\n"
"  calibrate             calibrate a camera from a ChArUco or chessboard recording\n"
"  board                 write a printable calibration target\n"
"  calib-convert IN OUT  convert OpenCV/ROS/KITTI calibration files to mvod JSON\n"
"  bench                 measure accuracy and speed against ground truth\n"
"  view                  draw the path, heading, state and rates of a running mvod\n"
"\n"
"Examples:\n"
"  mvod --source 'v4l2:/dev/video0?width=640&height=480&fps=30&format=YUYV' \\\n"
"       --calib webcam.json --lcm-url memq://\n"
"  mvod --source kitti:data/sequences/06 --gt data/poses/06.txt --scale gt \\\n"
"       --trajectory out.kitti --format kitti --plot out.png --lcm-url memq://\n"
"\n"
"Exit status: 0 on success, 1 on a runtime failure, 2 on a usage error.\n");
}

enum run_opt_id {
	OPT_LCM_URL = CLI_OPT_OWN, OPT_NO_LCM, OPT_POSE_CH, OPT_STATUS_CH, OPT_TRAJ, OPT_FORMAT,
	OPT_PLOT, OPT_LIST_CAMERAS,
};

static const struct option run_own_opts[] = {
	{"lcm-url", required_argument, NULL, OPT_LCM_URL},
	{"no-lcm", no_argument, NULL, OPT_NO_LCM},
	{"pose-channel", required_argument, NULL, OPT_POSE_CH},
	{"status-channel", required_argument, NULL, OPT_STATUS_CH},
	{"trajectory", required_argument, NULL, OPT_TRAJ},
	{"format", required_argument, NULL, OPT_FORMAT},
	{"plot", required_argument, NULL, OPT_PLOT},
	{"list-cameras", no_argument, NULL, OPT_LIST_CAMERAS},
	{NULL, 0, NULL, 0},
};

struct cli {
	struct mvod_run_opts run;
	const char *lcm_url, *pose_ch, *status_ch;
	int no_lcm, quiet, format_given, list_cameras;
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	struct mvod_run_opts *r = &c->run;
	switch (id) {
	case OPT_LCM_URL: c->lcm_url = arg; return 0;
	case OPT_NO_LCM: c->no_lcm = 1; return 0;
	case OPT_POSE_CH: c->pose_ch = arg; return 0;
	case OPT_STATUS_CH: c->status_ch = arg; return 0;
	case OPT_TRAJ: r->trajectory = arg; return 0;
	case OPT_FORMAT:
		c->format_given = 1;
		return mvod_traj_format_parse(arg, &r->traj_format)
			       ? cli_bad_value("format", arg, "tum or kitti")
			       : 0;
	case OPT_PLOT: r->plot = arg; return 0;
	case OPT_LIST_CAMERAS: c->list_cameras = 1; return 0;
	}
	return -ENOENT;
}

/* 0 to run, 1 when help/version was printed, -EINVAL on a usage error. */
static int parse_cli(int argc, char **argv, struct cli *c)
{
	mvod_run_opts_default(&c->run);
	int ret = cli_getopt(argc, argv, run_own_opts, parse_own, c, usage, &c->run, &c->quiet);
	if (ret || c->list_cameras)
		return ret;
	if (!c->run.source) {
		fprintf(stderr, "mvod: --source URI is required, e.g. --source file:video.mkv; "
				"see mvod --help\n");
		return -EINVAL;
	}
	if (!c->format_given && c->run.trajectory && cli_has_suffix(c->run.trajectory, ".kitti"))
		c->run.traj_format = MVOD_TRAJ_KITTI;
	return 0;
}

static void print_summary(const struct cli *c, const struct mvod_run_summary *s)
{
	printf("mvod: %lld frames in %.2f s (%.1f fps), %lld tracked, %lld held",
	       (long long)s->frames, s->wall_s, s->fps, (long long)s->tracked, (long long)s->held);
	if (s->live)
		printf(", %lld dropped", (long long)s->dropped);
	printf("\n");
	printf("mvod: ms per frame, mean (max):");
	for (int k = 0; k < MVOD_STAGE_COUNT; k++)
		printf(" %s %.2f (%.1f)", mvod_stage_names[k], s->stage_ms_mean[k], s->stage_ms_max[k]);
	printf("\nmvod: frame time median %.1f ms, 95th percentile %.1f ms\n", s->frame_ms_median,
	       s->frame_ms_p95);
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

int mvod_cmd_run(int argc, char **argv)
{
	struct cli c = {0};
	int ret = parse_cli(argc, argv, &c);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	cli_quiet_libraries();
	if (c.list_cameras) {
		mvod_capture_list_cameras(stdout);
		return EXIT_SUCCESS;
	}
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
