/*
 * mvod mount with the real binary on mvod-synth --board --floor (a board lying on a floor seen
 * by a still camera at an exact height, pitch and roll): the mount it writes against the exact
 * values, --scale height then taking it without --camera-height, and bad input (no board, a
 * board that stands, a board too far, no or the wrong intrinsics, a file it may not rewrite),
 * each a message and an exit status with the camera file left as it was.
 */
#include <math.h>
#include <stdbool.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/calib.h"

/* A floor mat (0.75 x 1.05 m) under a car-height camera looking down 20 deg, level. */
#define MAT "charuco:5x7:0.15:0.11:DICT_4X4_50"
#define MAT_FLOOR "1.6,20,0"
/* A sheet of paper (0.2 x 0.28 m) under a small robot's camera, pitched and rolled. */
#define SHEET "charuco:5x7:0.04:0.02:DICT_6X6_250"
#define SHEET_FLOOR "0.5,25,-3"

static char mat[400], sheet[400];

/*
 * mvod-synth --board spec --floor floor into DIR (tmpdir/name): n views, 1 grey level of noise,
 * the lens option lens (--fisheye K1,K2,K3,K4) or none (NULL).
 */
static void render_lens(const char *name, const char *spec, const char *floor, const char *n,
			const char *lens, char *uri, size_t len)
{
	char dir[256];
	snprintf(dir, sizeof(dir), "%s/%s", harness_tmpdir(), name);
	char *argv[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", dir, "--board", (char *)spec,
			"--floor", (char *)floor, "--views", (char *)n, "--format", "png", "--noise",
			"1", lens ? "--fisheye" : NULL, (char *)lens, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod-synth --floor %s failed (%d): %s", floor, r.status, r.err);
	snprintf(uri, len, "images:%s/images", dir);
}

static void render(const char *name, const char *spec, const char *floor, const char *n,
		   char *uri, size_t len)
{
	render_lens(name, spec, floor, n, NULL, uri, len);
}

static int setup(void **state)
{
	(void)state;
	render("mat", MAT, MAT_FLOOR, "6", mat, sizeof(mat));
	render("sheet", SHEET, SHEET_FLOOR, "6", sheet, sizeof(sheet));
	return 0;
}

/* A fresh copy of the camera file mvod-synth wrote beside the views of uri, at tmp/name. */
static const char *camera_copy(const char *uri, const char *name)
{
	char src[400];
	static char text[16384];
	snprintf(src, sizeof(src), "%.*s/calib.json", (int)(strlen(uri) - strlen("/images") -
							    strlen("images:")), uri + strlen("images:"));
	harness_read_file(src, text, sizeof(text));
	const char *path = harness_tmp_path(name);
	harness_write_file(path, text);
	return path;
}

static void mount_run(struct run_result *r, const char *uri, const char *board, const char *calib,
		      const char *extra)
{
	char *argv[12] = {(char *)harness_bin("MVOD"), "mount", "--source", (char *)uri, "--board",
			  (char *)board};
	int n = 6;
	if (calib) {
		argv[n++] = "--calib";
		argv[n++] = (char *)calib;
	}
	if (extra)
		argv[n++] = (char *)extra;
	argv[n] = NULL;
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited)
		fail_msg("mvod mount killed by signal %d: %s", r->status, r->err);
}

/* mvod mount fails with code and a message holding needle; the camera file is as it was. */
static void refused(const char *uri, const char *board, const char *calib, const char *extra,
		    int code, const char *needle)
{
	static char before[16384], after[16384];
	if (calib && access(calib, F_OK) == 0)
		harness_read_file(calib, before, sizeof(before));
	struct run_result r;
	mount_run(&r, uri, board, calib, extra);
	if (r.status != code || !strstr(r.err, needle))
		fail_msg("expected exit %d and '%s', got %d:\n%s%s", code, needle, r.status, r.out,
			 r.err);
	if (calib && access(calib, F_OK) == 0) {
		harness_read_file(calib, after, sizeof(after));
		assert_string_equal(after, before);
	}
}

/*
 * The mount written against the exact one. Tolerances: 0.3 % of the height and 0.15 deg,
 * 3 to 10 times the error measured (0.04 % and 0.03 deg on the mat, 0.04 % and 0.01 deg on
 * the sheet, 0.01 % and 0.01 deg with the fisheye) and within what --scale height needs (its height is the scale: 0.3 % of every
 * distance, a tenth of the 3 % target).
 */
static void measures(const char *uri, const char *board, double h, double pitch, double roll)
{
	const char *calib = camera_copy(uri, "measured.json");
	struct run_result r;
	mount_run(&r, uri, board, calib, NULL);
	if (r.status != 0)
		fail_msg("mvod mount failed (%d): %s", r.status, r.err);
	assert_non_null(strstr(r.out, "wrote the mount into"));
	struct mvod_camera cam;
	char err[512];
	assert_int_equal(mvod_calib_load(calib, &cam, err, sizeof(err)), 0);
	print_message("%s: height %.4f m (exact %.4f), pitch %.2f (%.2f), roll %.2f (%.2f) deg\n",
		      board, cam.mount_height_m, h, cam.mount_pitch_deg, pitch, cam.mount_roll_deg,
		      roll);
	assert_true(cam.has_mount);
	assert_true(fabs(cam.mount_height_m - h) <= 0.003 * h);
	assert_true(fabs(cam.mount_pitch_deg - pitch) <= 0.15);
	assert_true(fabs(cam.mount_roll_deg - roll) <= 0.15);
}

/* The camera file of uri converted by mvod calib-convert to tmp/name (OpenCV YAML or XML). */
static const char *camera_converted(const char *uri, const char *name)
{
	const char *json = camera_copy(uri, "to-convert.json");
	static char path[400];
	snprintf(path, sizeof(path), "%s", harness_tmp_path(name));
	char *argv[] = {(char *)harness_bin("MVOD"), "calib-convert", (char *)json, path, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (r.status != 0)
		fail_msg("calib-convert failed: %s", r.err);
	return path;
}

/*
 * Into an OpenCV YAML file: the mount added after the last key, every byte before it kept (a
 * comment and a key mvod does not read among them), measured as well as into mvod JSON; run
 * again, the values are replaced in place and nothing is added.
 */
static void test_measures_into_yaml(void **state)
{
	(void)state;
	static char before[16384], after[16384], again[16384];
	const char *calib = camera_converted(sheet, "sheet.yml");
	harness_read_file(calib, before, sizeof(before));
	strcat(before, "# kept as it is\navg_reprojection_error: 0.25\n");
	harness_write_file(calib, before);
	struct run_result r;
	mount_run(&r, sheet, SHEET, calib, NULL);
	if (r.status != 0)
		fail_msg("mvod mount failed (%d): %s", r.status, r.err);
	harness_read_file(calib, after, sizeof(after));
	assert_memory_equal(after, before, strlen(before));
	double h, pitch, roll;
	char end;
	assert_int_equal(sscanf(after + strlen(before), "mount_height_m: %lf\nmount_pitch_deg: %lf\n"
				"mount_roll_deg: %lf%c", &h, &pitch, &roll, &end), 4);
	struct mvod_camera cam;
	char err[512];
	assert_int_equal(mvod_calib_load(calib, &cam, err, sizeof(err)), 0);
	/* The tolerances of measures(), for the same views. */
	assert_true(cam.has_mount && cam.mount_height_m == h && cam.mount_pitch_deg == pitch);
	assert_true(fabs(h - 0.5) <= 0.003 * 0.5 && fabs(pitch - 25) <= 0.15 && fabs(roll + 3) <= 0.15);
	mount_run(&r, sheet, SHEET, calib, NULL);
	assert_int_equal(r.status, 0);
	harness_read_file(calib, again, sizeof(again));
	assert_memory_equal(again, before, strlen(before));
	assert_int_equal(sscanf(again + strlen(before), "mount_height_m: %lf\nmount_pitch_deg: %lf\n"
				"mount_roll_deg: %lf%c", &h, &pitch, &roll, &end), 4);
	int keys = 0;
	for (const char *q = again; (q = strstr(q, "mount_")); q++)
		keys++;
	assert_int_equal(keys, 3);
}

/*
 * Into OpenCV XML as mvod calib-convert (OpenCV's writer) lays it out: the mount added before
 * the closing tag, every byte before it kept (a comment among them), measured as well as into
 * mvod JSON; run again, the values replaced in place and nothing added.
 */
static void test_measures_into_xml(void **state)
{
	(void)state;
	static char before[16384], after[16384], again[16384];
	const char *calib = camera_converted(sheet, "sheet.xml");
	harness_read_file(calib, before, sizeof(before));
	char *close = strstr(before, "</opencv_storage>");
	assert_non_null(close);
	strcpy(close, "<!-- kept as it is -->\n");
	strcat(before, "</opencv_storage>\n");
	harness_write_file(calib, before);
	*strstr(before, "</opencv_storage>") = '\0';
	for (int run = 0; run < 2; run++) {
		struct run_result r;
		mount_run(&r, sheet, SHEET, calib, NULL);
		if (r.status != 0)
			fail_msg("mvod mount failed (%d): %s", r.status, r.err);
		harness_read_file(calib, run ? again : after, sizeof(after));
	}
	assert_memory_equal(after, before, strlen(before));
	double h, pitch, roll;
	char end[32];
	assert_int_equal(sscanf(after + strlen(before), "<mount_height_m>%lf</mount_height_m>\n"
				"<mount_pitch_deg>%lf</mount_pitch_deg>\n<mount_roll_deg>%lf"
				"</mount_roll_deg>\n%31s", &h, &pitch, &roll, end), 4);
	assert_string_equal(end, "</opencv_storage>");
	struct mvod_camera cam;
	char err[512];
	assert_int_equal(mvod_calib_load(calib, &cam, err, sizeof(err)), 0);
	/* The tolerances of measures(), for the same views. */
	assert_true(cam.has_mount && cam.mount_height_m == h && cam.mount_pitch_deg == pitch);
	assert_true(fabs(h - 0.5) <= 0.003 * 0.5 && fabs(pitch - 25) <= 0.15 && fabs(roll + 3) <= 0.15);
	/* The same measurement again: the same file, the values where they were. */
	assert_string_equal(again, after);
}

static void test_measures_mat(void **state)
{
	(void)state;
	measures(mat, MAT, 1.6, 20, 0);
}

static void test_measures_sheet(void **state)
{
	(void)state;
	measures(sheet, SHEET, 0.5, 25, -3);
}

/* A fisheye lens (Kannala-Brandt): the corners are undistorted by its own model. */
static void test_measures_fisheye(void **state)
{
	(void)state;
	char uri[400];
	render_lens("fisheye", SHEET, "0.4,35,2", "4", "0.1,-0.02,0.01,-0.002", uri, sizeof(uri));
	measures(uri, SHEET, 0.4, 35, 2);
}

/* The KITTI pose file of a camera 20 deg down going straight ahead 0.2 m a frame. */
static void pitched_path(const char *path, int frames)
{
	const double p = 20 * M_PI / 180, c = cos(p), s = sin(p);
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	for (int i = 0; i < frames; i++)
		fprintf(f, "1 0 0 0 0 %.9f %.9f 0 0 %.9f %.9f %.3f\n", c, s, -s, c, 0.2 * i);
	assert_int_equal(fclose(f), 0);
}

/*
 * The mount written, then mvod --scale height without --camera-height on a street seen by the
 * same camera 1.6 m up and 20 deg down: it says it takes the mount's height, and the path
 * comes out in metres. 30 frames (6 m): 0.9 % ATE measured with no scale alignment; without
 * the mount's pitch (--camera-height 1.6 alone) the same kind of run is 20 % off.
 */
static void test_scale_height_uses_mount(void **state)
{
	(void)state;
	const char *calib = camera_copy(mat, "street.json");
	struct run_result r;
	mount_run(&r, mat, MAT, calib, NULL);
	assert_int_equal(r.status, 0);
	struct mvod_camera cam;
	char err[512], poses[300], dir[300], video[320], gt[320], said[800];
	assert_int_equal(mvod_calib_load(calib, &cam, err, sizeof(err)), 0);
	snprintf(poses, sizeof(poses), "%s/pitched.kitti", harness_tmpdir());
	snprintf(dir, sizeof(dir), "%s/street", harness_tmpdir());
	pitched_path(poses, 30);
	harness_synth(dir, poses, 30, "mkv", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(gt, sizeof(gt), "%s/gt.tum", dir);
	const char *traj = harness_tmp_path("street.tum");
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", (char *)calib,
			"--gt", gt, "--scale", "height", "--trajectory", (char *)traj, "--no-lcm",
			NULL};
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod --scale height failed (%d): %s", r.status, r.err);
	snprintf(said, sizeof(said), "the camera is %.4f m above the ground (the mount in %s)",
		 cam.mount_height_m, calib);
	assert_non_null(strstr(r.err, said));
	struct traj_errors e;
	harness_compare(traj, gt, 0, &e);
	print_message("ATE %.4f m over %.2f m (%.2f %%)\n", e.ate_m, e.length_m,
		      100 * e.ate_m / e.length_m);
	/* 3 %: the bound for mvod-synth with a known height, over 3 times the 0.9 %. */
	assert_true(e.ate_m <= 0.03 * e.length_m);
	/* The same camera and mount as OpenCV YAML: taken from there the same way, no flag. */
	char yml[320];
	snprintf(yml, sizeof(yml), "%s/street.yml", harness_tmpdir());
	char *conv[] = {(char *)harness_bin("MVOD"), "calib-convert", (char *)calib, yml, NULL};
	assert_int_equal(harness_run(conv, &r), 0);
	assert_int_equal(r.status, 0);
	argv[4] = yml;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod --scale height with %s failed (%d): %s", yml, r.status, r.err);
	snprintf(said, sizeof(said), "the camera is %.4f m above the ground (the mount in %s)",
		 cam.mount_height_m, yml);
	assert_non_null(strstr(r.err, said));
	harness_compare(traj, gt, 0, &e);
	assert_true(e.ate_m <= 0.03 * e.length_m);
}

static void test_no_board(void **state)
{
	(void)state;
	const char *calib = camera_copy(sheet, "noboard.json");
	refused(sheet, "chessboard:9x6:0.025", calib, NULL, 1, "no 9x6 chessboard in 6 frames");
}

/* A board standing rather than lying: its plane 75 deg from the floor a mount could have. */
static void test_board_not_flat(void **state)
{
	(void)state;
	char uri[400];
	render("standing", SHEET, "0.5,75,0", "2", uri, sizeof(uri));
	refused(uri, SHEET, camera_copy(uri, "standing.json"), NULL, 1,
		"is not lying flat on the floor: its plane gives a pitch of 75.0 deg");
}

/*
 * A small chessboard 4-6 m away at a grazing angle: its corners come out 0.6-6 px off their
 * pose, the pose uncertain by 3-50 cm; either refusal says to bring the board closer.
 */
static void test_board_too_far(void **state)
{
	(void)state;
	char uri[400];
	render("far", "chessboard:4x3:0.15", "1.6,10,0", "3", uri, sizeof(uri));
	refused(uri, "chessboard:4x3:0.15", camera_copy(uri, "far.json"), NULL, 1,
		"move the board closer");
}

static void test_intrinsics_missing_or_wrong(void **state)
{
	(void)state;
	refused(sheet, SHEET, NULL, NULL, 2, "--calib FILE is required (the camera's intrinsics");
	refused(sheet, SHEET, harness_tmp_path("absent.json"), NULL, 1, "absent.json");
	/* Another camera's file: twice the size. */
	const char *big = harness_tmp_path("big.json");
	harness_write_file(big, "{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", "
				"\"image_size\": [1280, 960], \"K\": [[1152, 0, 639.5], [0, 1152, "
				"479.5], [0, 0, 1]], \"distortion\": []}\n");
	refused(sheet, SHEET, big, NULL, 1, "the camera file is for 1280x960 images but");
	/* Intrinsics mvod reads but whose format has no mount: refused unless --dry-run. */
	const char *pair = harness_tmp_path("pair.json");
	harness_write_file(pair, "[[[576, 0, 319.5], [0, 576, 239.5], [0, 0, 1]], []]\n");
	refused(sheet, SHEET, pair, NULL, 1, "convert it with mvod calib-convert");
	struct run_result r;
	mount_run(&r, sheet, SHEET, pair, "--dry-run");
	assert_int_equal(r.status, 0);
	assert_non_null(strstr(r.out, "--dry-run: "));
	/* The same measurement as with the file's own intrinsics (the pair holds the same). */
	const char *said = strstr(r.out, "height ");
	double h = 0;
	assert_true(said && sscanf(said, "height %lf m", &h) == 1);
	assert_true(fabs(h - 0.5) <= 0.003 * 0.5);
}

/*
 * A camera file that cannot be rewritten: on a full file system (root: a 64 KiB tmpfs filled
 * up, where the temporary file cannot be written), or read-only (others). Left whole.
 */
static void test_camera_file_unwritable(void **state)
{
	(void)state;
	char mnt[300], path[400], cmd[1200];
	snprintf(mnt, sizeof(mnt), "%s/tiny", harness_tmpdir());
	mkdir(mnt, 0700);
	snprintf(path, sizeof(path), "%s/cam.json", mnt);
	const char *calib = camera_copy(sheet, "unwritable.json");
	const bool root = geteuid() == 0;
	if (root && mount("tmpfs", mnt, "tmpfs", 0, "size=64k") != 0)
		skip();
	/* root: the file, then zeros until the file system is full; others: a read-only file. */
	if (root)
		snprintf(cmd, sizeof(cmd), "cp '%s' '%s' && (head -c 1000000 /dev/zero > '%s/fill'; "
			 "true)", calib, path, mnt);
	else
		snprintf(cmd, sizeof(cmd), "cp '%s' '%s' && chmod 0444 '%s'", calib, path, path);
	int sys = system(cmd);
	refused(sheet, SHEET, path, NULL, 1, root ? "No space left" : "cannot be rewritten");
	if (root)
		umount(mnt);
	assert_int_equal(sys, 0);
}

static void test_dry_run_and_help(void **state)
{
	(void)state;
	const char *calib = camera_copy(sheet, "dry.json");
	refused(sheet, SHEET, calib, "--dry-run", 0, "");
	struct run_result r;
	char *argv[] = {(char *)harness_bin("MVOD"), "mount", "--help", NULL};
	assert_int_equal(harness_run(argv, &r), 0);
	assert_int_equal(r.status, 0);
	assert_non_null(strstr(r.out, "pitch_deg  asin(n_z): positive when the camera looks down"));
	refused(sheet, SHEET, calib, "--board-thickness=0.5", 2, "--board-thickness");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_measures_mat),
		cmocka_unit_test(test_measures_sheet),
		cmocka_unit_test(test_measures_fisheye),
		cmocka_unit_test(test_measures_into_yaml),
		cmocka_unit_test(test_measures_into_xml),
		cmocka_unit_test(test_scale_height_uses_mount),
		cmocka_unit_test(test_no_board),
		cmocka_unit_test(test_board_not_flat),
		cmocka_unit_test(test_board_too_far),
		cmocka_unit_test(test_intrinsics_missing_or_wrong),
		cmocka_unit_test(test_camera_file_unwritable),
		cmocka_unit_test(test_dry_run_and_help),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
