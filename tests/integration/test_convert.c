/* mvod calib-convert, the real binary: each direction, operand order, and each refusal. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#include "mvod/calib.h"

#define ROS_YAML                                                                                  \
	"image_width: 752\nimage_height: 480\ncamera_name: narrow_stereo\n"                      \
	"camera_matrix:\n  rows: 3\n  cols: 3\n  data: [461.5, 0, 366.25, 0, 460.75, 248.125, 0, 0, 1]\n" \
	"distortion_model: plumb_bob\n"                                                          \
	"distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [-0.28, 0.07, 0.0002, 1.7e-05, 0]\n" \
	"rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"    \
	"projection_matrix:\n  rows: 3\n  cols: 4\n  data: [461.5, 0, 366.25, 0, 0, 460.75, 248.125, 0, 0, 0, 1, 0]\n"

static const char *path_in(const char *name)
{
	static char buf[4][256];
	static int k;
	k = (k + 1) % 4;
	snprintf(buf[k], sizeof(buf[k]), "%s/%s", harness_tmpdir(), name);
	return buf[k];
}

static struct run_result r;

static int convert(const char *a, const char *b, const char *c, const char *d)
{
	char *argv[] = {(char *)harness_bin("MVOD"), "calib-convert", (char *)a, (char *)b,
			(char *)c, (char *)d, NULL};
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited);
	return r.status;
}

/* ROS -> mvod JSON -> OpenCV YAML -> ROS again: the numbers survive every step exactly. */
static void ros_mvod_opencv_ros(void **state)
{
	(void)state;
	const char *ros = path_in("cam.yaml"), *json = path_in("cam.json");
	const char *cv = path_in("cam-cv.yml"), *ros2 = path_in("cam-ros.yaml");
	harness_write_file(ros, ROS_YAML);
	assert_int_equal(convert(ros, json, NULL, NULL), 0);
	assert_non_null(strstr(r.out, "ROS"));
	/* Options before the operands work as well as after them. */
	assert_int_equal(convert("--to", "opencv", json, cv), 0);
	assert_int_equal(convert(cv, ros2, "--to", "ros"), 0);
	struct mvod_camera cam;
	enum mvod_calib_format fmt;
	char err[256];
	assert_int_equal(mvod_calib_load_format(ros2, &cam, &fmt, err, sizeof(err)), 0);
	assert_int_equal(fmt, MVOD_CALIB_FMT_ROS);
	assert_int_equal(cam.width, 752);
	assert_int_equal(cam.height, 480);
	assert_true(cam.fx == 461.5 && cam.fy == 460.75 && cam.cx == 366.25 && cam.cy == 248.125);
	static const double k[5] = {-0.28, 0.07, 0.0002, 1.7e-05, 0};
	assert_int_equal(cam.n_dist, 5);
	/* mvod JSON keeps 15 significant digits when they read back within 1 ulp (cJSON). */
	for (int i = 0; i < 5; i++)
		assert_true(fabs(cam.dist[i] - k[i]) <= 2e-16 * fabs(k[i]));
}

/*
 * The mount, every way: ROS YAML -> mvod JSON -> OpenCV YAML -> OpenCV XML -> ROS YAML, each
 * read back with it; KITTI calib.txt has no place for it and says so.
 */
static void mount_carried(void **state)
{
	(void)state;
	static const char *const names[] = {"m.json", "m.yml", "m.xml", "m-ros.yaml"};
	char files[4][256], ros[256];
	for (int i = 0; i < 4; i++)
		snprintf(files[i], sizeof(files[i]), "%s/%s", harness_tmpdir(), names[i]);
	snprintf(ros, sizeof(ros), "%s/m.yaml", harness_tmpdir());
	harness_write_file(ros, ROS_YAML "mount_height_m: 1.65\nmount_pitch_deg: -2.25\n"
					  "mount_roll_deg: 0.5\n");
	const char *from = ros;
	for (int i = 0; i < 4; i++) {
		assert_int_equal(convert(from, files[i], i == 3 ? "--to" : NULL, i == 3 ? "ros" : NULL), 0);
		struct mvod_camera cam;
		char err[256];
		assert_int_equal(mvod_calib_load(files[i], &cam, err, sizeof(err)), 0);
		/* Exact: every writer prints a double that reads back as itself. */
		if (!cam.has_mount || cam.mount_height_m != 1.65 || cam.mount_pitch_deg != -2.25 ||
		    cam.mount_roll_deg != 0.5)
			fail_msg("%s: no mount or not 1.65 m, -2.25 deg, 0.5 deg", files[i]);
		from = files[i];
	}
	const char *kitti = path_in("m.txt");
	harness_write_file(ros, "image_width: 752\nimage_height: 480\ncamera_matrix:\n  rows: 3\n"
				"  cols: 3\n  data: [461.5, 0, 366.25, 0, 460.75, 248.125, 0, 0, 1]\n"
				"distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n"
				"mount_height_m: 1.65\n");
	assert_int_equal(convert(ros, kitti, NULL, NULL), 0);
	assert_non_null(strstr(r.err, "KITTI calib.txt has no place for the mount"));
}

/*
 * TUM monoVO's camera.txt (DSO's relative FOV form) -> mvod JSON -> a camera.txt by name, in
 * DSO's pixel form: the FOV lens carried both ways; ROS has no place for it and says so.
 */
static void dso_fov(void **state)
{
	(void)state;
	const char *in = path_in("mono.txt"), *json = path_in("fov.json");
	char dir[256], out[300];
	snprintf(dir, sizeof(dir), "%s/dso", harness_tmpdir());
	assert_int_equal(mkdir(dir, 0755), 0);
	snprintf(out, sizeof(out), "%s/camera.txt", dir);
	harness_write_file(in, "0.535719308086809 0.669566858850269 0.493248545285398 "
			       "0.500408664348414 0.897966326944875\n1280 1024\ncrop\n640 480\n");
	assert_int_equal(convert(in, json, "--to", "mvod"), 0);
	assert_non_null(strstr(r.out, "(DSO camera.txt): fov, 1280x1024"));
	assert_int_equal(convert(json, out, NULL, NULL), 0);
	char text[512];
	harness_read_file(out, text, sizeof(text));
	/* cJSON's 15 digits that read back within an ulp; the size and DSO's crop after. */
	if (strncmp(text, "FOV 685.72071", 13) != 0 || !strstr(text, " 0.897966326944875\n1280 "
							       "1024\ncrop\n1280 1024\n"))
		fail_msg("%s", text);
	struct mvod_camera a, b;
	char err[256];
	assert_int_equal(mvod_calib_load(in, &a, err, sizeof(err)), 0);
	assert_int_equal(mvod_calib_load(out, &b, err, sizeof(err)), 0);
	assert_int_equal(b.model, MVOD_CAM_FOV);
	assert_true(fabs(a.fx - b.fx) <= 2e-16 * a.fx && fabs(a.cy - b.cy) <= 2e-16 * a.cy);
	assert_true(b.dist[0] == a.dist[0]);
	assert_int_equal(convert(json, path_in("fov.yaml"), "--to", "ros"), 1);
	assert_non_null(strstr(r.err, "ROS camera_info has no FOV lens model"));
}

/* A refused conversion names the reason and leaves an existing OUT untouched. */
static void refusals_keep_out(void **state)
{
	(void)state;
	const char *ros = path_in("r.yaml"), *kitti = path_in("calib.txt");
	harness_write_file(ros, ROS_YAML);
	harness_write_file(kitti, "previous contents\n");
	assert_int_equal(convert(ros, kitti, NULL, NULL), 1); /* KITTI holds no distortion */
	assert_non_null(strstr(r.err, "distortion"));
	FILE *f = fopen(kitti, "r");
	char line[64] = "";
	assert_non_null(fgets(line, sizeof(line), f));
	fclose(f);
	assert_string_equal(line, "previous contents\n");

	assert_int_equal(convert(path_in("missing.yaml"), path_in("o.json"), NULL, NULL), 1);
	assert_non_null(strstr(r.err, "missing.yaml"));
	assert_int_equal(access(path_in("o.json"), F_OK), -1);
}

static void usage_errors(void **state)
{
	(void)state;
	assert_int_equal(convert(path_in("only-one.yaml"), NULL, NULL, NULL), 2);
	assert_non_null(strstr(r.err, "IN and OUT"));
	assert_int_equal(convert("a", "b", "c", NULL), 2);
	assert_int_equal(convert("a.yaml", "b.json", "--to", "png"), 2);
	assert_int_equal(convert("a.yaml", "b.bin", NULL, NULL), 2);
	assert_non_null(strstr(r.err, "--to"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(ros_mvod_opencv_ros),
		cmocka_unit_test(mount_carried),
		cmocka_unit_test(dso_fov),
		cmocka_unit_test(refusals_keep_out),
		cmocka_unit_test(usage_errors),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
