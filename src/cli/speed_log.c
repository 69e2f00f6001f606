/*
 * mvod speed-log: an LCM log of the mvod.speed_t a robot's wheels would report along a known
 * path (a ground truth), for --scale external without a robot: benchmarks, a robot's odometer
 * simulated with noise and bias, speed that stops or starts late.
 */
#include "cli/cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lcm/lcm.h>

#include "mvod/log.h"
#include "mvod/speed.h"
#include "mvod/traj.h"
#include "util/lines.h"

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "speed-log");
	fprintf(out,
"Writes the speed a robot's wheels would report along the ground-truth path GT, one\n"
"mvod.speed_t per pose from the second, into the LCM log OUT, for mvod --scale external\n"
"--speed-url 'file://OUT?mode=r' (or lcm-logplayer OUT): utime = the pose's time in\n"
"microseconds (the log's event times too), speed = the distance from the pose before over\n"
"the time between (m/s), distance = the path length so far (m).\n"
"\n"
"GT is TUM (its own times) or KITTI (the times from --times). Times must increase.\n"
"\n"
"  --times FILE          a KITTI sequence's times.txt (seconds, one per pose): needed for a\n"
"                        KITTI GT, refused with TUM\n"
"  --channel NAME        LCM channel (default " MVOD_DEFAULT_SPEED_CHANNEL
", mvod's --speed-channel)\n"
"  --no-distance         speed only (has_distance false): mvod integrates it\n"
"  --noise F             a real odometer: each step's distance times (1 + F g), g a standard\n"
"                        normal per message, F in [0, 1] (default 0)\n"
"  --bias F              each step's distance times (1 + F), F in [-0.5, 0.5] (default 0)\n"
"  --seed N              of g: the same N gives the same log on every machine (default 1)\n"
"  --samples N           only the first N messages: speed that stops arriving\n"
"  --from N              no message before the N-th (from 0): speed that starts late\n"
"\n");
	cli_usage_general(out);
	fprintf(out,
"Examples:\n"
"  mvod speed-log poses/07.txt speed07.lcmlog --times sequences/07/times.txt\n"
"  mvod bench --source kitti:sequences/07 --scale external \\\n"
"       --speed-url 'file://speed07.lcmlog?mode=r'\n"
"  mvod speed-log gt.tum noisy.lcmlog --noise 0.05 --bias 0.02\n"
"\n"
"OUT goes through mvod's output policy: GT or --times itself is refused, a symlink is\n"
"written through, a regular file is replaced only once the first message is written.\n"
"Exit status: 0 on success, 1 when OUT cannot be written, 2 on a usage error (a bad GT or\n"
"--times, OUT refused at start).\n");
}

enum speed_log_opt_id {
	OPT_TIMES = CLI_OPT_OWN, OPT_CHANNEL, OPT_NO_DISTANCE, OPT_NOISE, OPT_BIAS, OPT_SEED,
	OPT_SAMPLES, OPT_FROM,
};

static const struct option own_opts[] = {
	{"times", required_argument, NULL, OPT_TIMES},
	{"channel", required_argument, NULL, OPT_CHANNEL},
	{"no-distance", no_argument, NULL, OPT_NO_DISTANCE},
	{"noise", required_argument, NULL, OPT_NOISE},
	{"bias", required_argument, NULL, OPT_BIAS},
	{"seed", required_argument, NULL, OPT_SEED},
	{"samples", required_argument, NULL, OPT_SAMPLES},
	{"from", required_argument, NULL, OPT_FROM},
	{NULL, 0, NULL, 0},
};

struct cli {
	struct mvod_speed_log_opts o;
	const char *times, *files[2]; /* GT, OUT */
	int quiet;
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	long v;
	int ret = 0;
	switch (id) {
	case OPT_TIMES: c->times = arg; return 0;
	case OPT_NO_DISTANCE: c->o.no_distance = true; return 0;
	case OPT_NOISE: return cli_parse_double("noise", arg, 0, 1, &c->o.noise);
	case OPT_BIAS: return cli_parse_double("bias", arg, -0.5, 0.5, &c->o.bias);
	case OPT_CHANNEL:
		c->o.channel = arg;
		if (!*arg || strlen(arg) > LCM_MAX_CHANNEL_NAME_LENGTH)
			return cli_bad_value("channel", arg, "a channel name of 1 to 63 characters");
		return 0;
	case OPT_SEED:
		ret = cli_parse_int("seed", arg, 0, 1L << 62, &v);
		c->o.seed = (uint64_t)v;
		return ret;
	case OPT_SAMPLES:
	case OPT_FROM:
		ret = cli_parse_int(id == OPT_FROM ? "from" : "samples", arg, id == OPT_FROM ? 0 : 1,
				    1L << 40, &v);
		*(id == OPT_FROM ? &c->o.from : &c->o.samples) = v;
		return ret;
	}
	return -ENOENT;
}

/* One time of a times.txt line into t[*n]: a number, no more lines than poses. */
struct times {
	struct mvod_traj *t;
	int n;
};

static int read_time(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct times *ts = ctx;
	char *end;
	double v = strtod(line, &end);
	while (*end == ' ' || *end == '\t')
		end++;
	if (end == line || *end)
		return mvod_errf(err, errlen, -EINVAL, "line %zu: \"%s\" is not a time in seconds",
				 lineno, line);
	if (ts->n == ts->t->n)
		return mvod_errf(err, errlen, -EINVAL, "more times than the %d poses of the ground "
				 "truth", ts->t->n);
	ts->t->t[ts->n++] = v;
	return 0;
}

/* The ground truth and its times, as the format needs: -EINVAL after saying what is wrong. */
static int load_gt(const struct cli *c, struct mvod_traj *t)
{
	char err[MVOD_ERR_MAX];
	const char *gt = c->files[0];
	if (mvod_traj_load(gt, t, err, sizeof(err))) {
		fprintf(stderr, "%s: %s\n", cli_prog, err);
		return -EINVAL;
	}
	bool kitti = t->format == MVOD_TRAJ_KITTI;
	if (kitti != (c->times != NULL)) {
		fprintf(stderr, "%s: %s is %s: %s\n", cli_prog, gt, kitti ? "KITTI" : "TUM",
			kitti ? "its poses carry no times: pass the sequence's --times times.txt"
			      : "it has its own times: drop --times");
		return -EINVAL;
	}
	struct times ts = {t, 0};
	int ret = kitti ? mvod_lines_each(c->times, "--times", read_time, &ts, err, sizeof(err)) : 0;
	if (!ret && kitti && ts.n != t->n)
		ret = mvod_errf(err, sizeof(err), -EINVAL, "%d times for the %d poses of %s", ts.n,
				t->n, gt);
	if (ret)
		fprintf(stderr, "%s: --times %s: %s\n", cli_prog, c->times, err);
	return ret ? -EINVAL : 0;
}

/* Usage errors found in the ground truth: too short, or --samples and --from leaving nothing. */
static int check_count(const struct cli *c, const struct mvod_traj *t)
{
	long n = t->n - 1;
	if (c->o.samples >= 0 && c->o.samples < n)
		n = c->o.samples;
	if (n > c->o.from)
		return 0;
	fprintf(stderr, "%s: no message to write: %s has %d poses (a message per pose from the "
			"second)%s\n", cli_prog, c->files[0], t->n,
		c->o.samples >= 0 || c->o.from ? ", and --samples and --from leave none" : "");
	return -EINVAL;
}

int mvod_cmd_speed_log(int argc, char **argv)
{
	struct cli c = {0};
	mvod_speed_log_opts_default(&c.o);
	int ret = cli_getopt_args(argc, argv, own_opts, parse_own, &c, usage, NULL, &c.quiet,
				  c.files, 2, "GT and OUT.lcmlog");
	if (ret)
		return ret > 0 ? EXIT_SUCCESS : EXIT_USAGE;
	struct mvod_traj t = {0};
	/* The inputs are read, and so noted, before OUT is checked: OUT may be neither. */
	ret = load_gt(&c, &t);
	ret = ret ? ret : check_count(&c, &t);
	ret = ret ? ret : cli_check_writable("OUT", c.files[1]);
	if (ret) {
		mvod_traj_free(&t);
		return EXIT_USAGE;
	}
	char err[MVOD_ERR_MAX];
	int n = mvod_speed_log_write(c.files[1], t.n, t.t, t.pose, &c.o, err, sizeof(err));
	if (n < 0)
		LOG(ERROR, "%s", err);
	else if (!c.quiet)
		printf("%s: wrote %d mvod.speed_t on %s to %s, %.3f s to %.3f s\n", cli_prog, n,
		       c.o.channel, c.files[1], t.t[1 + c.o.from], t.t[c.o.from + n]);
	mvod_traj_free(&t);
	return n < 0 ? EXIT_FAILURE : EXIT_SUCCESS;
}
