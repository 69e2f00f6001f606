/*
 * The config file: every key lands in its own field (checked by field name, not through the
 * table, so a wrong offset in the table fails here); each kind of error names file, line and
 * key; flags override the file; --print-config output parses back to the same settings; the
 * example mvod.conf shipped for the service parses and sets every key; and the VO's options
 * that clash with one another are refused before any run (check.c).
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mvod/config.h"
#include "mvod/vo.h"

static int parse(const char *text, struct mvod_config *c, char *err, size_t errlen)
{
	return mvod_config_parse_buffer("test.conf", text, strlen(text), c, err, errlen);
}

static void parse_ok(const char *text, struct mvod_config *c)
{
	char err[512] = "";
	if (parse(text, c, err, sizeof(err)))
		fail_msg("%s: in\n%s", err, text);
}

/* Every key at a value other than its default. */
static const char every_key[] =
	"[source]\n"
	"uri = file:clip.mkv?realtime=1\n"
	"max-frames = 1234\n"
	"gt = gt.tum\n"
	"clock = realtime\n"
	"[calibration]\n"
	"file = calib.json\n"
	"[vo]\n"
	"scale = gt\n"
	"camera-height = 1.65\n"
	"speed-channel = SPD\n"
	"speed-url = file:///tmp/s.lcmlog?mode=r\n"
	"features = 777\n"
	"frontend = klt\n"
	"tracks = 333\n"
	"ratio = 0.65\n"
	"detector = sift\n"
	"matcher = flann-ratio\n"
	"best = 150\n"
	"robust = ransac\n"
	"ransac-px = 2.5\n"
	"confidence = 0.99\n"
	"mode = twoview\n" /* not the default (map), so that the key is seen to be read */
	"min-parallax = 3\n"
	"resize = 0.5\n"
	"blur = 5\n"
	"ba-sync = yes\n"
	"[lcm]\n"
	"enabled = no\n"
	"url = memq://\n"
	"pose-channel = P\n"
	"status-channel = S\n"
	"status-rate = 12.5\n"
	"[output]\n"
	"trajectory = out.kitti\n"
	"format = tum\n"
	"plot = out.png\n"
	"frame = ros\n"
	"camera-to-body = 0.1,0,0.2,-0.5,0.5,-0.5,0.5\n"
	"[log]\n"
	"level = debug\n"
	"quiet = yes\n";

static void assert_every_key(const struct mvod_config *c)
{
	assert_string_equal(c->run.source, "file:clip.mkv?realtime=1");
	assert_int_equal(c->run.max_frames, 1234);
	assert_string_equal(c->run.gt, "gt.tum");
	assert_string_equal(c->run.calib, "calib.json");
	assert_int_equal(c->run.vo.scale_mode, MVOD_SCALE_MODE_GT);
	assert_true(c->run.vo.camera_height_m == 1.65);
	assert_string_equal(c->run.speed_channel, "SPD");
	assert_string_equal(c->run.speed_url, "file:///tmp/s.lcmlog?mode=r");
	assert_int_equal(c->run.vo.max_features, 777);
	assert_int_equal(c->run.vo.frontend, MVOD_FRONTEND_KLT);
	assert_int_equal(c->run.vo.max_tracks, 333);
	assert_true(c->run.vo.ratio == 0.65);
	assert_int_equal(c->run.vo.detector, MVOD_DETECTOR_SIFT);
	assert_int_equal(c->run.vo.matcher, MVOD_MATCHER_FLANN_RATIO);
	assert_int_equal(c->run.vo.best_n, 150);
	assert_int_equal(c->run.vo.robust, MVOD_ROBUST_RANSAC);
	assert_true(c->run.vo.ransac_px == 2.5);
	assert_true(c->run.vo.ransac_conf == 0.99);
	assert_true(c->run.vo.min_parallax_px == 3);
	assert_int_equal(c->run.vo.mode, MVOD_VO_TWOVIEW);
	assert_true(c->run.vo.resize == 0.5);
	assert_int_equal(c->run.vo.blur_ksize, 5);
	assert_true(c->run.vo.ba_sync);
	assert_false(c->lcm_enabled);
	assert_string_equal(c->lcm_url, "memq://");
	assert_string_equal(c->pose_channel, "P");
	assert_string_equal(c->status_channel, "S");
	assert_true(c->run.status_hz == 12.5);
	assert_string_equal(c->run.trajectory, "out.kitti");
	/* Given explicitly, so the .kitti name does not decide it. */
	assert_int_equal(c->run.traj_format, MVOD_TRAJ_TUM);
	assert_string_equal(c->run.plot, "out.png");
	assert_int_equal(c->run.clock, MVOD_CLOCK_REALTIME);
	assert_int_equal(c->run.axes, MVOD_AXES_ROS);
	assert_string_equal(c->run.camera_to_body, "0.1,0,0.2,-0.5,0.5,-0.5,0.5");
	assert_int_equal(c->log_level, MVOD_LOG_DEBUG);
	assert_true(c->quiet);
}

static void test_every_key(void **state)
{
	(void)state;
	struct mvod_config c;
	parse_ok(every_key, &c);
	mvod_config_finish(&c);
	assert_every_key(&c);
	/* ... and the text above names every key there is. */
	assert_true(c.set == (1ULL << mvod_config_nkeys) - 1);
	mvod_config_fini(&c);
}

static void test_defaults_and_format_from_name(void **state)
{
	(void)state;
	struct mvod_config c;
	char err[256];
	assert_int_equal(parse("# nothing\n\n; at all\n", &c, err, sizeof(err)), 0);
	assert_null(c.run.source);
	assert_int_equal(c.run.vo.max_features, 2000);
	assert_int_equal(c.run.vo.mode, MVOD_VO_MAP); /* issue 12: map mode is the default */
	assert_true(c.run.status_hz == 1);
	assert_true(c.lcm_enabled);
	assert_string_equal(c.pose_channel, "MVOD_POSE");
	mvod_config_fini(&c);
	assert_int_equal(parse("[output]\ntrajectory = a.kitti\n", &c, err, sizeof(err)), 0);
	mvod_config_finish(&c);
	assert_int_equal(c.run.traj_format, MVOD_TRAJ_KITTI);
	mvod_config_fini(&c);
}

/* Indented keys are keys (inih alone would take them for continuation lines); comments go. */
static void test_layout(void **state)
{
	(void)state;
	struct mvod_config c;
	const char *text = "\xef\xbb\xbf[vo]\r\n  features = 300\r\n\tratio=0.7 ; inline\n"
			   "[vo]\nresize = 0.5\n[source]\nuri = file:a;b.mkv\nmax-frames = 5";
	parse_ok(text, &c);
	assert_int_equal(c.run.vo.max_features, 300);
	assert_true(c.run.vo.ratio == 0.7);
	assert_true(c.run.vo.resize == 0.5);
	/* ';' without a blank before it is part of the value. */
	assert_string_equal(c.run.source, "file:a;b.mkv");
	/* The last line needs no newline. */
	assert_int_equal(c.run.max_frames, 5);
	mvod_config_fini(&c);
}

/* A bad file fails with the defaults left in out and a message holding every needle. */
static void expect_error(const char *text, const char *n1, const char *n2)
{
	struct mvod_config c;
	char err[512] = "";
	assert_int_equal(parse(text, &c, err, sizeof(err)), -EINVAL);
	if (!strstr(err, n1) || (n2 && !strstr(err, n2)))
		fail_msg("for %s: expected \"%s\" and \"%s\" in: %s", text, n1, n2 ? n2 : "", err);
	assert_null(c.run.source);
	assert_int_equal(c.run.vo.max_features, 2000);
	assert_int_equal(c.owned, 0);
}

static void test_errors(void **state)
{
	(void)state;
	const char *pre = "[source]\nuri = file:x.mkv\n";
	char text[512];
#define WITH(line) (snprintf(text, sizeof(text), "%s%s", pre, line), text)
	expect_error(WITH("[camera]\nuri = x\n"), "test.conf:4: [camera] uri: unknown section",
		     NULL);
	expect_error(WITH("[vo]\nfeatres = 100\n"), "test.conf:4: [vo] featres: unknown key",
		     "[vo] has mode, scale, frontend, detector, matcher, features");
	expect_error(WITH("[vo]\nfeatures = many\n"),
		     "test.conf:4: [vo] features = many: expected an integer in [50, 100000]", NULL);
	expect_error(WITH("[vo]\nfeatures = 12.5\n"), "test.conf:4: [vo] features", "an integer");
	expect_error(WITH("[vo]\nratio = 1.5\n"),
		     "test.conf:4: [vo] ratio = 1.5: expected a number in [0.1, 1]", NULL);
	expect_error(WITH("[vo]\nratio = nan\n"), "test.conf:4: [vo] ratio", NULL);
	expect_error(WITH("[vo]\nblur = 4\n"), "test.conf:4: [vo] blur = 4: expected an odd", NULL);
	expect_error(WITH("[lcm]\nenabled = maybe\n"), "test.conf:4: [lcm] enabled",
		     "true or false");
	expect_error(WITH("[vo]\nmatcher = kd\n"), "test.conf:4: [vo] matcher", "flann-ratio");
	expect_error(WITH("[vo]\nrobust = lmeds\n"), "test.conf:4: [vo] robust",
		     "magsac or ransac");
	expect_error(WITH("[log]\nlevel = loud\n"), "test.conf:4: [log] level",
		     "error, warn, info or debug");
	expect_error(WITH("[lcm]\nstatus-rate = 0\n"), "test.conf:4: [lcm] status-rate",
		     "[0.1, 100]");
	expect_error(WITH("[lcm]\npose-channel =\n"), "test.conf:4: [lcm] pose-channel",
		     "non-empty");
	/* Checked when read, not when the run starts: a usage error like any other value. */
	expect_error(WITH("[output]\ncamera-to-body = 1,2,3\n"),
		     "test.conf:4: [output] camera-to-body = 1,2,3: expected 7 numbers "
		     "x,y,z,qx,qy,qz,qw", NULL);
	expect_error(WITH("[output]\ncamera-to-body = 0,0,0,0,0,0,2\n"),
		     "[output] camera-to-body = 0,0,0,0,0,0,2: expected 7 numbers",
		     "quaternion's norm is 2");
	expect_error(WITH("[vo]\nfeatures\n"), "test.conf:4: not a [section] or key = value", NULL);
	expect_error(WITH("[vo\nfeatures = 100\n"), "test.conf:3: not a [section]", NULL);
	expect_error("features = 100\n", "test.conf:1: features: every key belongs in a section",
		     NULL);
	/* The first error is the one reported, whichever kind comes first. */
	expect_error(WITH("junk\n[vo]\nratio = 9\n"), "test.conf:3: not a [section]", NULL);
	expect_error(WITH("[vo]\nratio = 9\njunk\n"), "test.conf:4: [vo] ratio = 9", NULL);
#undef WITH
}

static void test_lines_inih_would_mangle(void **state)
{
	(void)state;
	char text[400] = "[output]\ntrajectory = /";
	memset(text + strlen(text), 'a', 250);
	expect_error(text, "test.conf:2: line longer than 198 characters", NULL);
	struct mvod_config c;
	char err[256] = "";
	const char nul[] = "[vo]\nfeatures = 1\0 00\n";
	assert_int_equal(mvod_config_parse_buffer("test.conf", nul, sizeof(nul) - 1, &c, err,
						  sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "test.conf:2: a NUL byte"));
}

/* Flags (set with mvod_config_set, as the command line does) win over the file. */
static void test_flags_override_file(void **state)
{
	(void)state;
	struct mvod_config file, flags;
	char err[256] = "";
	parse_ok(every_key, &file);
	mvod_config_default(&flags);
	int features = -1, lcm = -1;
	for (int k = 0; k < mvod_config_nkeys; k++) {
		if (strcmp(mvod_config_keys[k].flag, "features") == 0)
			features = k;
		if (strcmp(mvod_config_keys[k].flag, "no-lcm") == 0)
			lcm = k;
	}
	assert_int_equal(mvod_config_set(&flags, features, "100", err, sizeof(err)), 0);
	assert_int_equal(mvod_config_set(&flags, lcm, NULL, err, sizeof(err)), 0);
	mvod_config_override(&file, &flags);
	assert_int_equal(file.run.vo.max_features, 100);
	assert_false(file.lcm_enabled);
	/* What the flags did not name stays as the file said. */
	assert_true(file.run.vo.ratio == 0.65);
	assert_string_equal(file.run.source, "file:clip.mkv?realtime=1");
	assert_int_equal(mvod_config_set(&flags, features, "10", err, sizeof(err)), -EINVAL);
	assert_string_equal(err, "an integer in [50, 100000]");
	mvod_config_fini(&file);
	mvod_config_fini(&flags);
}

/* The printed text of c, in a malloc'd string. */
static char *print(const struct mvod_config *c)
{
	char *buf = NULL;
	size_t len = 0;
	char err[256] = "";
	FILE *f = open_memstream(&buf, &len);
	assert_non_null(f);
	if (mvod_config_print(c, f, err, sizeof(err)))
		fail_msg("%s", err);
	fclose(f);
	return buf;
}

static void test_print_round_trip(void **state)
{
	(void)state;
	struct mvod_config a, b;
	parse_ok(every_key, &a);
	a.run.vo.ratio = 0.1 + 0.2; /* 0.30000000000000004: the printer must not round it */
	char *text = print(&a);
	parse_ok(text, &b);
	assert_true(b.run.vo.ratio == a.run.vo.ratio);
	char *again = print(&b);
	assert_string_equal(text, again);
	b.run.vo.ratio = 0.65;
	assert_every_key(&b);
	free(text);
	free(again);
	mvod_config_fini(&a);
	mvod_config_fini(&b);
	/* The defaults, with their empty (NULL) paths, round-trip too. */
	mvod_config_default(&a);
	text = print(&a);
	parse_ok(text, &b);
	assert_null(b.run.source);
	assert_null(b.lcm_url);
	again = print(&b);
	assert_string_equal(text, again);
	free(text);
	free(again);
	mvod_config_fini(&b);
}

/*
 * --print-config does not pin what follows other keys: a file made from the printout of a run
 * to x.tum, edited to trajectory = x.kitti, writes KITTI (issue 18). Given, the format stays.
 */
static void test_print_leaves_format_derived(void **state)
{
	(void)state;
	struct mvod_config a, b;
	parse_ok("[output]\ntrajectory = x.tum\n", &a);
	mvod_config_finish(&a);
	char *text = print(&a), printed[4096], edited[8192];
	snprintf(printed, sizeof(printed), "%s", text);
	free(text);
	assert_non_null(strstr(printed, "\n# format = tum  (not set"));
	char *at = strstr(printed, "trajectory = x.tum");
	assert_non_null(at);
	*at = '\0';
	snprintf(edited, sizeof(edited), "%strajectory = x.kitti%s", printed,
		 at + strlen("trajectory = x.tum"));
	parse_ok(edited, &b);
	mvod_config_finish(&b);
	assert_int_equal(b.run.traj_format, MVOD_TRAJ_KITTI);
	mvod_config_fini(&a);
	mvod_config_fini(&b);
	parse_ok("[output]\ntrajectory = x.kitti\nformat = tum\n", &a);
	mvod_config_finish(&a);
	text = print(&a);
	assert_non_null(strstr(text, "\nformat = tum\n"));
	parse_ok(text, &b);
	mvod_config_finish(&b);
	assert_int_equal(b.run.traj_format, MVOD_TRAJ_TUM);
	free(text);
	mvod_config_fini(&a);
	mvod_config_fini(&b);
}

/*
 * --print-config says which front end auto runs and why, as an INI comment that keeps the key
 * auto when the printout is read back: klt unless an option only orb and sift have differs
 * from its default. --features is not one of them (`[vo] features = 1500` switched auto to
 * orb, 8x slower); an explicit front end needs no comment.
 */
static void test_print_frontend(void **state)
{
	(void)state;
	static const struct {
		const char *file, *line;
	} cases[] = {
		{"", "\nfrontend = auto  ; runs klt: none of detector, matcher, ratio, best (orb and "
		     "sift only) set\n"},
		{"[vo]\nfeatures = 1500\n", "\nfrontend = auto  ; runs klt: none of detector, matcher, "
		 "ratio, best (orb and sift only) set\n"},
		{"[vo]\nmatcher = flann\n", "\nfrontend = auto  ; runs orb: matcher = flann (orb and sift "
		 "only) set\n"},
		{"[vo]\nmode = twoview\ndetector = sift\nfeatures = 500\n", "\nfrontend = auto  ; runs "
		 "sift: detector = sift (orb and sift only) set\n"},
		{"[vo]\nfrontend = klt\nfeatures = 500\n", "\nfrontend = klt\n"},
		{"[vo]\nfrontend = orb\n", "\nfrontend = orb\n"},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		struct mvod_config a, b;
		parse_ok(cases[i].file, &a);
		char *text = print(&a);
		if (!strstr(text, cases[i].line))
			fail_msg("case %zu: no \"%s\" in:\n%s", i, cases[i].line, text);
		parse_ok(text, &b); /* the comment is a comment: the key reads back as it was */
		assert_int_equal(b.run.vo.frontend, a.run.vo.frontend);
		free(text);
		mvod_config_fini(&a);
		mvod_config_fini(&b);
	}
}

/* A value INI cannot carry is refused rather than printed into something else. */
static void test_print_refuses(void **state)
{
	(void)state;
	static const char *const bad[] = {"a ;b", "a\nb", " lead", "trail "};
	for (int i = 0; i < 4; i++) {
		struct mvod_config c;
		mvod_config_default(&c);
		c.run.trajectory = bad[i];
		char err[256] = "";
		FILE *f = fopen("/dev/null", "w");
		assert_int_equal(mvod_config_print(&c, f, err, sizeof(err)), -EINVAL);
		fclose(f);
		assert_non_null(strstr(err, "[output] trajectory"));
	}
}

/* The index of [section] key in mvod_config_keys. */
static int key_index(const char *section, const char *key)
{
	for (int k = 0; k < mvod_config_nkeys; k++)
		if (!strcmp(mvod_config_keys[k].section, section) && !strcmp(mvod_config_keys[k].key, key))
			return k;
	fail_msg("no key [%s] %s", section, key);
	return -1;
}

/* systemd/mvod.conf, installed as the example: parses, and sets every key. */
static void test_example_config(void **state)
{
	(void)state;
	const char *src = getenv("MVOD_SRCDIR");
	if (!src)
		fail_msg("MVOD_SRCDIR is not set: run the tests through meson test");
	char path[512], err[512] = "";
	snprintf(path, sizeof(path), "%s/systemd/mvod.conf", src);
	struct mvod_config c;
	if (mvod_config_load(path, &c, err, sizeof(err)))
		fail_msg("%s", err);
	/* Every key but the derived format, which must follow an edited trajectory name. */
	int fmt = key_index("output", "format");
	assert_true(c.set == (((1ULL << mvod_config_nkeys) - 1) & ~(1ULL << fmt)));
	assert_non_null(c.run.source);
	/* The config owns the file's trajectory string: put it back for mvod_config_fini. */
	const char *owned = c.run.trajectory;
	c.run.trajectory = "/var/lib/mvod/x.kitti";
	mvod_config_finish(&c);
	assert_int_equal(c.run.traj_format, MVOD_TRAJ_KITTI);
	c.run.trajectory = owned;
	mvod_config_fini(&c);
	assert_int_equal(mvod_config_load("/nonexistent/mvod.conf", &c, err, sizeof(err)), -ENOENT);
	assert_non_null(strstr(err, "/nonexistent/mvod.conf"));
}

/* p is refused, and the message names every flag of needles (NULL-ended). */
static void refused(const struct mvod_vo_params *p, const char *const *needles)
{
	char err[256] = "";
	assert_int_equal(mvod_config_check_frontend(p, err, sizeof(err)), -EINVAL);
	for (int i = 0; needles[i]; i++)
		if (!strstr(err, needles[i]))
			fail_msg("'%s' not in: %s", needles[i], err);
}

/*
 * The clashes of the VO's options (check.c), refused before anything runs, each message
 * naming the flags: map mode with SIFT (its map keeps ORB descriptors; else mapmode.c refuses
 * it only once the run has started), --tracks where ORB runs, a descriptor option with
 * --frontend klt. Their neighbours pass: SIFT in two-view mode, --tracks with KLT, the
 * defaults. (tests/integration/test_refusals.c has the same case on the command line.)
 */
static void test_option_clashes(void **state)
{
	(void)state;
	struct mvod_vo_params d, p;
	mvod_vo_params_default(&d);
	char err[256];
	assert_int_equal(mvod_config_check_frontend(&d, err, sizeof(err)), 0);
	p = d;
	p.detector = MVOD_DETECTOR_SIFT;
	refused(&p, (const char *const[]){"--mode map", "sift", "--mode twoview", NULL});
	p.mode = MVOD_VO_TWOVIEW;
	assert_int_equal(mvod_config_check_frontend(&p, err, sizeof(err)), 0);
	p = d;
	p.frontend = MVOD_FRONTEND_ORB;
	p.max_tracks = 300;
	refused(&p, (const char *const[]){"--tracks", "--frontend orb", NULL});
	p.frontend = MVOD_FRONTEND_KLT;
	assert_int_equal(mvod_config_check_frontend(&p, err, sizeof(err)), 0);
	p = d;
	p.frontend = MVOD_FRONTEND_KLT;
	p.matcher = MVOD_MATCHER_FLANN;
	refused(&p, (const char *const[]){"--matcher", "--frontend klt", NULL});
	/* --features is orb's and sift's count: with klt the run warns, it is no clash. */
	p = d;
	p.frontend = MVOD_FRONTEND_KLT;
	p.max_features = 500;
	assert_int_equal(mvod_config_check_frontend(&p, err, sizeof(err)), 0);
	p.max_tracks = 300;
	p.frontend = MVOD_FRONTEND_AUTO;
	assert_int_equal(mvod_config_check_frontend(&p, err, sizeof(err)), 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_every_key),
		cmocka_unit_test(test_defaults_and_format_from_name),
		cmocka_unit_test(test_layout),
		cmocka_unit_test(test_errors),
		cmocka_unit_test(test_lines_inih_would_mangle),
		cmocka_unit_test(test_flags_override_file),
		cmocka_unit_test(test_print_round_trip),
		cmocka_unit_test(test_print_refuses),
		cmocka_unit_test(test_print_leaves_format_derived),
		cmocka_unit_test(test_print_frontend),
		cmocka_unit_test(test_example_config),
		cmocka_unit_test(test_option_clashes),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
