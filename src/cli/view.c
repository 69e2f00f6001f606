/*
 * mvod view: draws what a running mvod publishes, or an LCM log of it: the path, the heading,
 * the tracking state and the rates. It only subscribes; it never sends.
 */
#include "cli/cli.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <lcm/lcm.h>

#include "mvod/ipc.h"
#include "mvod/log.h"
#include "mvod/view.h"
#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_status2_t.h"
#include "mvod_status_t.h"
#include "util/output.h"

/* A window is redrawn at most this often: enough to follow a robot, little CPU. */
#define REFRESH_MS 100
/* How long the headless loop waits for a message before it looks at the stop flag again. */
#define IDLE_WAIT_MS 250
#define DEFAULT_EVERY 30
#define DEFAULT_MAX_POSES 20000
#define WINDOW_NAME "mvod view"

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
	(void)sig;
	stop_requested = 1;
}

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "view");
	fprintf(out,
"Draws what a running mvod publishes over LCM, or an LCM log of it: the path seen from\n"
"above (x right, z forward; metres with --scale gt, else units of the first step, labelled\n"
"free scale), the heading, the tracking state, mvod's frame rate and the rate poses arrive\n"
"at, dropped frames, features and inliers, stage times, memory and uptime. It only\n"
"subscribes: it never sends anything.\n"
"\n"
"  --lcm-url URL         LCM provider (default: $LCM_DEFAULT_URL, then LCM's default), the\n"
"                        same as the watched mvod's; an LCM log plays back with\n"
"                        file:///PATH.lcmlog?mode=r (&speed=0: as fast as possible; the\n"
"                        default speed=1 replays in real time), and the viewer ends with it\n"
"  --pose-channel NAME   channel of mvod.pose_t (default MVOD_POSE); mvod.pose2_t is read\n"
"                        on NAME2 (MVOD_POSE2), and v1 only from logs without v2\n"
"  --status-channel NAME channel of mvod.status_t (default MVOD_STATUS; status2_t on NAME2)\n"
"  --png FILE            no window: draw into FILE (rewritten whole, never half-written)\n"
"  --every N             with --png: redraw FILE after every N poses (default %d), and at exit\n"
"  --max-poses N         points of the path kept; longer runs are thinned evenly, so memory\n"
"                        stays fixed (default %d)\n"
"\n", DEFAULT_EVERY, DEFAULT_MAX_POSES);
	cli_usage_general(out);
	fprintf(out,
"Without --png it opens a window (DISPLAY or WAYLAND_DISPLAY must be set), redrawn up to\n"
"10 times a second; q or Esc closes it. At the end of a log the window stays until closed.\n"
"SIGINT and SIGTERM end it after a last redraw of the PNG.\n"
"\n"
"Examples:\n"
"  mvod view --lcm-url 'udpm://239.255.76.67:7667?ttl=0'\n"
"  mvod view --lcm-url 'file:///tmp/run.lcmlog?mode=r&speed=0' --png path.png --every 100\n"
"\n"
"Exit status: 0 on success, 1 on a run-time fault, 2 on a usage error (--png refused at\n"
"start too).\n");
}

enum view_opt_id {
	OPT_LCM_URL = CLI_OPT_OWN, OPT_POSE_CH, OPT_STATUS_CH, OPT_PNG, OPT_EVERY, OPT_MAX_POSES,
};

static const struct option own_opts[] = {
	{"lcm-url", required_argument, NULL, OPT_LCM_URL},
	{"pose-channel", required_argument, NULL, OPT_POSE_CH},
	{"status-channel", required_argument, NULL, OPT_STATUS_CH},
	{"png", required_argument, NULL, OPT_PNG},
	{"every", required_argument, NULL, OPT_EVERY},
	{"max-poses", required_argument, NULL, OPT_MAX_POSES},
	{NULL, 0, NULL, 0},
};

struct cli {
	const char *url, *pose_ch, *status_ch, *png;
	long every, max_poses;
	int every_given, quiet;
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	switch (id) {
	case OPT_LCM_URL: c->url = arg; return 0;
	case OPT_POSE_CH: c->pose_ch = arg; return 0;
	case OPT_STATUS_CH: c->status_ch = arg; return 0;
	case OPT_PNG: c->png = arg; return 0;
	case OPT_EVERY:
		c->every_given = 1;
		return cli_parse_int("every", arg, 1, 1L << 40, &c->every);
	case OPT_MAX_POSES: return cli_parse_int("max-poses", arg, 100, 10000000, &c->max_poses);
	}
	return -ENOENT;
}

/* A file:// log is what the view reads: --png may not be it (util/output.h). */
static int note_log(const char *url)
{
	char path[4096], mode;
	return mvod_lcm_file_url(url, path, sizeof(path), &mode) ? 0 : mvod_input_note(path);
}

static bool have_display(void)
{
	const char *x = getenv("DISPLAY"), *w = getenv("WAYLAND_DISPLAY");
	return (x && *x) || (w && *w);
}

/* 0 to run, 1 when help/version was printed, -EINVAL on a usage error. */
static int parse_cli(int argc, char **argv, struct cli *c)
{
	*c = (struct cli){.every = DEFAULT_EVERY, .max_poses = DEFAULT_MAX_POSES};
	int ret = cli_getopt(argc, argv, own_opts, parse_own, c, usage, NULL, &c->quiet);
	if (ret)
		return ret;
	if (c->every_given && !c->png) {
		fprintf(stderr, "%s: --every needs --png FILE\n", cli_prog);
		return -EINVAL;
	}
	char path[4096], mode = 'r';
	if (c->url && !mvod_lcm_file_url(c->url, path, sizeof(path), &mode) && mode != 'r') {
		fprintf(stderr, "%s: --lcm-url %s: the viewer only reads logs; use mode=r (writing "
				"would truncate the log)\n", cli_prog, c->url);
		return -EINVAL;
	}
	if (!c->png && !have_display()) {
		fprintf(stderr, "%s: no display (DISPLAY and WAYLAND_DISPLAY are unset): pass "
				"--png FILE [--every N] to draw into a PNG instead of a window\n",
			cli_prog);
		return -EINVAL;
	}
	return 0;
}

struct viewer {
	const struct cli *c;
	const char *url;  /* as given, or from LCM_DEFAULT_URL; NULL for LCM's default */
	bool is_log;      /* a file:// URL: its end ends the viewer */
	bool end_of_log;
	int64_t cut_at;   /* the log is cut short at this byte; -1 when whole */
	lcm_t *lcm;
	mvod_pose_t_subscription_t *pose_sub;
	mvod_status_t_subscription_t *status_sub;
	mvod_pose2_t_subscription_t *pose2_sub;
	mvod_status2_t_subscription_t *status2_sub;
	struct mvod_view view;
	struct mvod_view_labels labels;
	char title[256];
	int64_t png_poses; /* poses drawn in the last PNG */
	int png_writes, png_failed;
};

static int64_t now_us(void)
{
	/* LCM stamps recv_utime from the wall clock. */
	struct timespec ts;
	clock_gettime(CLOCK_REALTIME, &ts);
	return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static void write_png(struct viewer *w)
{
	w->png_poses = w->view.poses;
	int ret = mvod_view_write_png(&w->view, now_us(), &w->labels, w->c->png);
	if (ret) {
		LOG(ERROR, "cannot write %s: %s", w->c->png, strerror(-ret));
		w->png_failed = ret;
		return;
	}
	w->png_failed = 0;
	w->png_writes++;
}

static void after_pose(struct viewer *w)
{
	if (w->c->png && w->view.poses - w->png_poses >= w->c->every)
		write_png(w);
}

static void on_pose2(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_pose2_t *msg,
		     void *user)
{
	(void)ch;
	mvod_view_add_pose2(&((struct viewer *)user)->view, msg, rbuf->recv_utime);
	after_pose(user);
}

static void on_status2(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_status2_t *msg,
		       void *user)
{
	(void)rbuf;
	(void)ch;
	mvod_view_add_status2(&((struct viewer *)user)->view, msg);
}

/* v1, from logs of an mvod that published nothing else (ignored once v2 came). */
static void on_pose(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_pose_t *msg,
		    void *user)
{
	(void)ch;
	mvod_view_add_pose(&((struct viewer *)user)->view, msg, rbuf->recv_utime);
	after_pose(user);
}

static void on_status(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_status_t *msg,
		      void *user)
{
	(void)rbuf;
	(void)ch;
	mvod_view_add_status(&((struct viewer *)user)->view, msg);
}

/* lcm_handle_timeout failed: a signal, the end of a log, or a broken provider. */
static int stream_ended(struct viewer *w)
{
	if (stop_requested)
		return 0;
	if (w->is_log) {
		w->end_of_log = true;
		w->labels.banner = "end of log";
		return 0;
	}
	LOG(ERROR, "LCM stopped delivering messages on %s", w->url ? w->url : "the default URL");
	return -EIO;
}

static int run_headless(struct viewer *w)
{
	while (!stop_requested) {
		if (lcm_handle_timeout(w->lcm, IDLE_WAIT_MS) < 0)
			return stream_ended(w);
	}
	return 0;
}

/* Messages are handled between redraws; after the end of a log the picture stays. */
static int run_window(struct viewer *w)
{
	char err[MVOD_ERR_MAX];
	int ret = mvod_view_display_check(err, sizeof(err));
	if (!ret)
		ret = mvod_view_window_open(WINDOW_NAME, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s: pass --png FILE to draw into a PNG instead", err);
		return ret;
	}
	bool quit = false;
	int64_t next_draw = 0;
	while (!stop_requested && !quit && !ret) {
		int64_t wait = (next_draw - now_us()) / 1000;
		if (!w->end_of_log && lcm_handle_timeout(w->lcm, wait > 0 ? (int)wait : 0) < 0)
			ret = stream_ended(w);
		if (now_us() < next_draw && !w->end_of_log)
			continue;
		next_draw = now_us() + REFRESH_MS * 1000;
		int sret = mvod_view_window_show(WINDOW_NAME, &w->view, now_us(), &w->labels,
						 w->end_of_log ? REFRESH_MS : 1, &quit);
		ret = ret ? ret : sret;
	}
	mvod_view_window_close(WINDOW_NAME);
	return ret;
}

static int open_lcm(struct viewer *w)
{
	w->lcm = lcm_create(w->c->url);
	if (!w->lcm) {
		LOG(ERROR, "cannot open LCM at %s: check --lcm-url (e.g. udpm://239.255.76.67:7667, "
			   "or file:///tmp/mvod.lcmlog?mode=r&speed=0 for a log, which must exist and "
			   "hold at least one message)", w->url ? w->url : "the default URL");
		return -EINVAL;
	}
	const char *pc = w->c->pose_ch ? w->c->pose_ch : MVOD_DEFAULT_POSE_CHANNEL;
	const char *sc = w->c->status_ch ? w->c->status_ch : MVOD_DEFAULT_STATUS_CHANNEL;
	char pc2[LCM_MAX_CHANNEL_NAME_LENGTH + 2], sc2[sizeof(pc2)]; /* v2: the name + "2" */
	snprintf(pc2, sizeof(pc2), "%s2", pc);
	snprintf(sc2, sizeof(sc2), "%s2", sc);
	w->pose_sub = mvod_pose_t_subscribe(w->lcm, pc, on_pose, w);
	w->status_sub = mvod_status_t_subscribe(w->lcm, sc, on_status, w);
	w->pose2_sub = mvod_pose2_t_subscribe(w->lcm, pc2, on_pose2, w);
	w->status2_sub = mvod_status2_t_subscribe(w->lcm, sc2, on_status2, w);
	if (!w->pose_sub || !w->status_sub || !w->pose2_sub || !w->status2_sub) {
		LOG(ERROR, "cannot subscribe to %s, %s, %s and %s", pc, sc, pc2, sc2);
		return -EINVAL;
	}
	snprintf(w->title, sizeof(w->title), "mvod view: %s on %s", pc,
		 w->url ? w->url : "the default LCM URL");
	w->labels.title = w->title;
	return 0;
}

/*
 * A log is checked before LCM reads it (ipc/log_check.h): corrupt, empty or unreadable, it is
 * refused (LCM would only say "check --lcm-url"); only cut short at its end (a writer stopped
 * mid-event), LCM reads it up to there, safely.
 */
static int check_log(struct viewer *w)
{
	char path[4096], mode, err[512];
	struct mvod_lcmlog_check c;
	int ret = mvod_lcm_file_url(w->url, path, sizeof(path), &mode);
	if (!ret)
		ret = mvod_lcmlog_vet(path, &c, err, sizeof(err));
	else
		snprintf(err, sizeof(err), "%s: %s", w->url, strerror(-ret));
	if (ret) {
		LOG(ERROR, "%s%s", err, ret == -ENODATA ? ": nothing to show" : "");
		return ret;
	}
	w->cut_at = c.cut ? c.bad_offset : -1;
	if (c.cut)
		LOG(WARN, "log %s is cut short at byte %lld: %s; the %lld whole events before it "
			  "are shown", path, (long long)c.bad_offset, c.why, (long long)c.events);
	return 0;
}

static void close_lcm(struct viewer *w)
{
	if (!w->lcm)
		return;
	if (w->pose_sub)
		mvod_pose_t_unsubscribe(w->lcm, w->pose_sub);
	if (w->status_sub)
		mvod_status_t_unsubscribe(w->lcm, w->status_sub);
	if (w->pose2_sub)
		mvod_pose2_t_unsubscribe(w->lcm, w->pose2_sub);
	if (w->status2_sub)
		mvod_status2_t_unsubscribe(w->lcm, w->status2_sub);
	lcm_destroy(w->lcm);
}

static void print_summary(const struct viewer *w)
{
	printf("mvod view: %lld poses, %lld status messages, last state %s",
	       (long long)w->view.poses, (long long)w->view.statuses,
	       mvod_run_state_name(w->view.state));
	if (w->view.state == MVOD_RUN_STOPPING)
		printf(" (after %s)", mvod_run_state_name(w->view.last_state));
	printf(", tracked in %lld of %lld poses", (long long)w->view.tracked,
	       (long long)w->view.poses);
	if (w->c->png)
		printf("; %s written %d times", w->c->png, w->png_writes);
	if (w->end_of_log && w->cut_at >= 0)
		printf(" (end of log, cut short at byte %lld)\n", (long long)w->cut_at);
	else
		printf("%s\n", w->end_of_log ? " (end of log)" : "");
	if (w->view.refused)
		LOG(WARN, "%lld pose messages held no pose and are not drawn; the first, %s",
		    (long long)w->view.refused, w->view.refused_why);
}

static int view(const struct cli *c)
{
	struct viewer w = {.c = c, .url = c->url ? c->url : getenv("LCM_DEFAULT_URL"),
			   .cut_at = -1};
	w.is_log = w.url && strncmp(w.url, "file://", 7) == 0;
	if (mvod_view_init(&w.view, (int)c->max_poses)) {
		LOG(ERROR, "out of memory for a path of %ld poses", c->max_poses);
		return EXIT_FAILURE;
	}
	int ret = w.is_log ? check_log(&w) : 0;
	if (!ret)
		ret = open_lcm(&w);
	if (!ret)
		ret = c->png ? run_headless(&w) : run_window(&w);
	if (!ret && c->png) {
		write_png(&w);
		ret = w.png_failed;
	}
	if (!ret && !c->quiet)
		print_summary(&w);
	close_lcm(&w);
	mvod_view_fini(&w.view);
	return ret ? EXIT_FAILURE : EXIT_SUCCESS;
}

int mvod_cmd_view(int argc, char **argv)
{
	struct cli c;
	int ret = parse_cli(argc, argv, &c);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	if (c.png && (note_log(c.url ? c.url : getenv("LCM_DEFAULT_URL")) ||
		      cli_check_writable("--png", c.png)))
		return EXIT_USAGE;
	/* No SA_RESTART: the signal interrupts LCM's wait at once. */
	struct sigaction sa = {.sa_handler = on_signal};
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	return view(&c);
}
