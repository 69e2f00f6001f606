/*
 * Calibration formats beyond mvod JSON: OpenCV FileStorage YAML/XML, ROS camera_info, the JSON
 * [K, dist] pair and the KITTI writer; round trips, dispatch by content, and each malformation.
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"
#include "util/output.h"

#include "mvod/calib.h"

static const char *dir;

static int setup(void **state)
{
	(void)state;
	dir = harness_tmpdir();
	return 0;
}

static const char *path_of(const char *name)
{
	static char path[256];
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	return path;
}

static const char *write_file(const char *name, const char *text)
{
	const char *path = path_of(name);
	harness_write_file(path, text);
	return path;
}

/*
 * Values with long decimal expansions, so a writer that rounds anywhere shows. The OpenCV, ROS
 * and KITTI writers print 17 significant digits or the shortest decimal that reads back
 * exactly, and strtod rounds correctly, so their round trips must be bit-exact (tolerance 0).
 * cJSON (mvod JSON) prints 15 digits whenever they read back within DBL_EPSILON relative, so
 * its round trip may be off by one unit in the last place: measured 1.7e-16 relative
 * (-0.010000000000000002 read back as -0.01); the bound is 2 DBL_EPSILON.
 */
#define EXACT 0.0
#define CJSON_REL (2 * DBL_EPSILON)

static struct mvod_camera pinhole(int n_dist)
{
	struct mvod_camera c = {.width = 1280, .height = 720, .fx = 1000.0 / 3, .fy = 2000.0 / 7,
				.cx = 639.1 + 1e-9, .cy = 359.9 / 3, .model = MVOD_CAM_PINHOLE_RADTAN,
				.n_dist = n_dist};
	for (int i = 0; i < n_dist; i++)
		c.dist[i] = (i % 2 ? -1.0 : 1.0) / (3.0 + i) * pow(10, -(i % 3));
	return c;
}

static struct mvod_camera fisheye(void)
{
	struct mvod_camera c = pinhole(4);
	c.model = MVOD_CAM_FISHEYE_KB4;
	return c;
}

static void assert_close(const char *what, double want, double got, double rel)
{
	if (fabs(got - want) > rel * fabs(want))
		fail_msg("%s: wrote %.17g, read %.17g", what, want, got);
}

/* want_n: coefficients read back (a writer may pad: ROS plumb_bob always has 5). */
static void assert_same_camera(const struct mvod_camera *a, const struct mvod_camera *b, int want_n,
			       double rel)
{
	assert_int_equal(a->width, b->width);
	assert_int_equal(a->height, b->height);
	assert_close("fx", a->fx, b->fx, rel);
	assert_close("fy", a->fy, b->fy, rel);
	assert_close("cx", a->cx, b->cx, rel);
	assert_close("cy", a->cy, b->cy, rel);
	assert_int_equal(a->model, b->model);
	assert_int_equal(b->n_dist, want_n);
	for (int i = 0; i < want_n; i++)
		assert_close("coefficient", i < a->n_dist ? a->dist[i] : 0.0, b->dist[i], rel);
}

typedef int (*save_fn)(const char *path, const struct mvod_camera *cam, char *err, size_t errlen);

static void round_trip_within(save_fn save, const char *name, const struct mvod_camera *cam, int want_n,
			      enum mvod_calib_format want_fmt, double rel)
{
	char err[256] = "";
	const char *path = path_of(name);
	assert_int_equal(save(path, cam, err, sizeof(err)), 0);
	struct mvod_camera back;
	enum mvod_calib_format fmt;
	if (mvod_calib_load_format(path, &back, &fmt, err, sizeof(err)))
		fail_msg("%s: %s", name, err);
	assert_int_equal(fmt, want_fmt);
	assert_same_camera(cam, &back, want_n, rel);
	/* Read, so an input of this process: the next round writes the same name again. */
	mvod_inputs_forget();
}

static void round_trip(save_fn save, const char *name, const struct mvod_camera *cam, int want_n,
		       enum mvod_calib_format want_fmt)
{
	round_trip_within(save, name, cam, want_n, want_fmt, EXACT);
}

static int save_mvod(const char *path, const struct mvod_camera *cam, char *err, size_t errlen)
{
	(void)err;
	(void)errlen;
	return mvod_calib_save(path, cam, NULL);
}

static void test_round_trip_mvod_opencv(void **state)
{
	(void)state;
	static const int counts[] = {0, 4, 5, 8, 12, 14};
	for (size_t i = 0; i < sizeof(counts) / sizeof(counts[0]); i++) {
		struct mvod_camera c = pinhole(counts[i]);
		round_trip_within(save_mvod, "rt.json", &c, counts[i], MVOD_CALIB_FMT_MVOD, CJSON_REL);
		/* OpenCV has no empty coefficient list: none is written as five zeros. */
		int n = counts[i] ? counts[i] : 5;
		round_trip(mvod_calib_save_opencv, "rt.yml", &c, n, MVOD_CALIB_FMT_OPENCV);
		round_trip(mvod_calib_save_opencv, "rt.xml", &c, n, MVOD_CALIB_FMT_OPENCV);
	}
	struct mvod_camera f = fisheye();
	round_trip_within(save_mvod, "fe.json", &f, 4, MVOD_CALIB_FMT_MVOD, CJSON_REL);
	round_trip(mvod_calib_save_opencv, "fe.yml", &f, 4, MVOD_CALIB_FMT_OPENCV);
}

static void test_round_trip_ros(void **state)
{
	(void)state;
	struct mvod_camera plumb = pinhole(5), short4 = pinhole(4), rational = pinhole(8);
	struct mvod_camera fe = fisheye();
	round_trip(mvod_calib_save_ros, "plumb.yaml", &plumb, 5, MVOD_CALIB_FMT_ROS);
	round_trip(mvod_calib_save_ros, "short4.yaml", &short4, 5, MVOD_CALIB_FMT_ROS);
	round_trip(mvod_calib_save_ros, "rational.yaml", &rational, 8, MVOD_CALIB_FMT_ROS);
	round_trip(mvod_calib_save_ros, "equidistant.yaml", &fe, 4, MVOD_CALIB_FMT_ROS);

	/* What ROS's tools see: the distortion model by its ROS name. */
	FILE *f = fopen(path_of("equidistant.yaml"), "r");
	assert_non_null(f);
	char line[256];
	int found = 0;
	while (fgets(line, sizeof(line), f))
		found |= strcmp(line, "distortion_model: equidistant\n") == 0;
	fclose(f);
	assert_true(found);

	/* Zero thin-prism terms can be dropped; non-zero ones cannot. */
	struct mvod_camera c12 = pinhole(8);
	c12.n_dist = 12;
	round_trip(mvod_calib_save_ros, "c12.yaml", &c12, 8, MVOD_CALIB_FMT_ROS);
	c12.dist[10] = 1e-3;
	char err[256] = "";
	assert_int_equal(mvod_calib_save_ros(path_of("c12b.yaml"), &c12, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "thin-prism"));
	struct mvod_camera nosize = pinhole(5);
	nosize.width = nosize.height = 0;
	assert_int_equal(mvod_calib_save_ros(path_of("nosize.yaml"), &nosize, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "image size"));
}

static void test_kitti_writer(void **state)
{
	(void)state;
	struct mvod_camera c = pinhole(0);
	c.width = c.height = 0; /* calib.txt has no image size */
	round_trip(mvod_calib_save_kitti, "calib.txt", &c, 0, MVOD_CALIB_FMT_KITTI);
	/* Zero coefficients are no distortion. */
	struct mvod_camera z = c;
	z.n_dist = 5;
	round_trip(mvod_calib_save_kitti, "calib0.txt", &z, 0, MVOD_CALIB_FMT_KITTI);

	char err[256] = "";
	struct mvod_camera d = pinhole(5), fe = fisheye();
	assert_int_equal(mvod_calib_save_kitti(path_of("calib_d.txt"), &d, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "distortion"));
	assert_int_equal(mvod_calib_save_kitti(path_of("calib_f.txt"), &fe, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "fisheye"));
	FILE *f = fopen(path_of("calib_d.txt"), "r");
	assert_null(f); /* a refused write leaves nothing behind */
}

static void test_json_pair(void **state)
{
	(void)state;
	static const struct {
		const char *text;
		enum mvod_cam_model model;
		int n;
	} ok[] = {
		{"[[[500,0,320],[0,501,240],[0,0,1]], [0.1,-0.2,0.001,0.002,0.03]]", MVOD_CAM_PINHOLE_RADTAN, 5},
		{"[[500,0,320,0,501,240,0,0,1], [[0.1,-0.2,0.001,0.002,0.03]]]", MVOD_CAM_PINHOLE_RADTAN, 5},
		{"{\"K\": [[500,0,320],[0,501,240],[0,0,1]], \"dist\": []}", MVOD_CAM_PINHOLE_RADTAN, 0},
		{"{\"K\": [[500,0,320],[0,501,240],[0,0,1]], \"dist\": [0.1,-0.2,0.001,0.002], "
		 "\"model\": \"fisheye-kb4\"}", MVOD_CAM_FISHEYE_KB4, 4},
	};
	for (size_t i = 0; i < sizeof(ok) / sizeof(ok[0]); i++) {
		const char *p = write_file("pair.json", ok[i].text);
		struct mvod_camera c;
		enum mvod_calib_format fmt;
		char err[256] = "";
		if (mvod_calib_load_format(p, &c, &fmt, err, sizeof(err)))
			fail_msg("%s: %s", ok[i].text, err);
		assert_int_equal(fmt, MVOD_CALIB_FMT_PAIR);
		assert_true(c.fx == 500 && c.fy == 501 && c.cx == 320 && c.cy == 240);
		assert_int_equal(c.width, 0);
		assert_int_equal(c.model, ok[i].model);
		assert_int_equal(c.n_dist, ok[i].n);
		assert_true(ok[i].n == 0 || c.dist[0] == 0.1);
	}
}

/* The file is named in every reason, and so is the key at fault. */
static void expect_error(const char *name, const char *text, const char *needle)
{
	const char *p = write_file(name, text);
	struct mvod_camera c = {.fx = 42};
	char err[512] = "";
	assert_int_equal(mvod_calib_load(p, &c, err, sizeof(err)), -EINVAL);
	if (!strstr(err, name) || !strstr(err, needle) || strchr(err, '\n'))
		fail_msg("%s: reason '%s' should name the file and '%s' on one line", text, err, needle);
	assert_true(c.fx == 42); /* untouched on failure */
}

static void test_malformed_pair(void **state)
{
	(void)state;
	expect_error("p1.json", "[[[500,0,320],[0,501,240],[0,0,1]]]", "[K, dist]");
	expect_error("p2.json", "[[[500,0,320],[0,501,240]], [0,0,0,0]]", "element 0 (K)");
	expect_error("p3.json", "[[[500,1,320],[0,501,240],[0,0,1]], [0,0,0,0]]", "element 0 (K)");
	expect_error("p4.json", "[[[0,0,320],[0,501,240],[0,0,1]], [0,0,0,0]]", "element 0 (K)");
	expect_error("p5.json", "[[[500,0,320],[0,501,240],[0,0,1]], [0,0,0]]", "element 1 (distortion)");
	expect_error("p6.json", "[[[500,0,320],[0,501,240],[0,0,1]], [0,\"x\",0,0]]", "element 1");
	expect_error("p7.json", "{\"K\": [[500,0,320],[0,501,240],[0,0,1]]}", "\"dist\"");
	expect_error("p8.json", "{\"K\": [[500,0,320],[0,501,240],[0,0,1]], \"dist\": [0,0,0,0,0], "
				"\"model\": \"fisheye-kb4\"}", "\"dist\"");
	expect_error("p9.json", "{\"K\": [[500,0,320],[0,501,240],[0,0,1]], \"dist\": [], "
				"\"model\": \"kb8\"}", "\"model\"");
	expect_error("p10.json", "[[[500,0,320],[0,501,240],[0,0,1]], [0,0,0,0]", "JSON");
}

#define YAML_HEAD "%YAML:1.0\nimage_width: 640\nimage_height: 480\n"
#define OCV_K "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: "
#define OCV_D "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: "
#define GOOD_K "[ 500., 0., 320., 0., 501., 240., 0., 0., 1. ]\n"
#define GOOD_D "[ 0.1, -0.2, 0., 0., 0.03 ]\n"

static void test_malformed_opencv(void **state)
{
	(void)state;
	expect_error("o1.yml", YAML_HEAD OCV_D GOOD_D, "camera_matrix");
	expect_error("o2.yml", YAML_HEAD OCV_K GOOD_K, "distortion_coefficients");
	expect_error("o3.yml", YAML_HEAD OCV_K "[ 500., 0., 320., 0., 501., 240., 0., 0. ]\n" OCV_D GOOD_D,
		     "camera_matrix");
	expect_error("o4.yml", YAML_HEAD OCV_K "[ 500., 0., 320., 0., 501., 240., 0., 0., 2. ]\n" OCV_D
		     GOOD_D, "camera_matrix");
	expect_error("o5.yml", YAML_HEAD OCV_K "[ -500., 0., 320., 0., 501., 240., 0., 0., 1. ]\n" OCV_D
		     GOOD_D, "camera_matrix");
	expect_error("o6.yml", YAML_HEAD OCV_K "[ 500., 0., 320., 7., 501., 240., 0., 0., 1. ]\n" OCV_D
		     GOOD_D, "camera_matrix");
	expect_error("o7.yml", YAML_HEAD OCV_K "[ .nan, 0., 320., 0., 501., 240., 0., 0., 1. ]\n" OCV_D
		     GOOD_D, "not finite");
	expect_error("o8.yml", YAML_HEAD OCV_K "[ 500., 0., abc, 0., 501., 240., 0., 0., 1. ]\n" OCV_D
		     GOOD_D, "not a number");
	expect_error("o9.yml", YAML_HEAD OCV_K GOOD_K
		     "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 3\n   dt: d\n"
		     "   data: [ 0.1, -0.2, 0. ]\n", "distortion_coefficients");
	expect_error("o10.yml", YAML_HEAD OCV_K GOOD_K
		     "distortion_coefficients: !!opencv-matrix\n   rows: 2\n   cols: 2\n   dt: d\n"
		     "   data: [ 0.1, -0.2, 0., 0. ]\n", "distortion_coefficients");
	expect_error("o11.yml", YAML_HEAD OCV_K GOOD_K OCV_D GOOD_D "distortion_model: fisheye\n",
		     "distortion_coefficients");
	expect_error("o12.yml", YAML_HEAD OCV_K GOOD_K OCV_D GOOD_D "distortion_model: kb8\n",
		     "distortion_model");
	expect_error("o13.yml", "%YAML:1.0\nimage_width: -3\n" OCV_K GOOD_K OCV_D GOOD_D, "image_width");
	expect_error("o14.yml", "%YAML:1.0\ncamera_matrix: 7\n" OCV_D GOOD_D, "camera_matrix");
	expect_error("o15.yml", "%YAML:1.0\ncamera_matrix: [ 1, 2\n", "unknown calibration format");
	expect_error("o16.xml", "<?xml version=\"1.0\"?>\n<opencv_storage>\n<imagelist>\n\"a.jpg\"\n"
				"</imagelist>\n</opencv_storage>\n", "camera_matrix");
	/*
	 * OpenCV 4.6's reader looped forever on these (found by fuzzing): a scalar, not a map; and
	 * a document end ("...") followed by text that starts no new document, on line 10.
	 */
	expect_error("o18.yml", "%YAML:1.0\n -L-\n-\n ", "no \"camera_matrix\" key");
	expect_error("o19.yml", YAML_HEAD OCV_K GOOD_K "...\n-x\n", "YAML error at line 10");
	char many[2048];
	snprintf(many, sizeof(many), "%s%s%s", YAML_HEAD OCV_K GOOD_K,
		 "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 15\n   dt: d\n"
		 "   data: [ 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0. ]\n", "");
	expect_error("o17.yml", many, "distortion_coefficients");
}

#define ROS_HEAD "image_width: 640\nimage_height: 480\ncamera_name: cam\n"
#define ROS_K "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [500, 0, 320, 0, 501, 240, 0, 0, 1]\n"

static void test_ros_reader(void **state)
{
	(void)state;
	/* As camera_calibration writes it, four-coefficient equidistant included. */
	const char *p = write_file("ros.yaml", ROS_HEAD ROS_K "distortion_model: equidistant\n"
				   "distortion_coefficients:\n  rows: 1\n  cols: 4\n  data: [0.1, -0.01, 0.001, -0.0001]\n"
				   "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
				   "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [500, 0, 320, 0, 0, 501, 240, 0, 0, 0, 1, 0]\n");
	struct mvod_camera c;
	enum mvod_calib_format fmt;
	char err[256] = "";
	if (mvod_calib_load_format(p, &c, &fmt, err, sizeof(err)))
		fail_msg("%s", err);
	assert_int_equal(fmt, MVOD_CALIB_FMT_ROS);
	assert_int_equal(c.model, MVOD_CAM_FISHEYE_KB4);
	assert_int_equal(c.width, 640);
	assert_int_equal(c.n_dist, 4);
	assert_true(c.fx == 500 && c.fy == 501 && c.cx == 320 && c.cy == 240 && c.dist[3] == -0.0001);

	expect_error("r1.yaml", ROS_HEAD "distortion_model: plumb_bob\n", "camera_matrix");
	expect_error("r2.yaml", ROS_HEAD ROS_K "distortion_model: plumb_bob\ndistortion_coefficients:\n"
				"  rows: 1\n  cols: 5\n  data: [0.1, 0, 0]\n", "distortion_coefficients");
	expect_error("r3.yaml", ROS_HEAD ROS_K "distortion_model: plumb_bob\ndistortion_coefficients:\n"
				"  rows: 1\n  cols: 5\n", "distortion_coefficients");
	expect_error("r4.yaml", "image_width: wide\n" ROS_K, "image_width");
}

static void load_ok(const char *name, const char *text, struct mvod_camera *c, enum mvod_calib_format want)
{
	enum mvod_calib_format fmt;
	char err[512] = "";
	if (mvod_calib_load_format(write_file(name, text), c, &fmt, err, sizeof(err)))
		fail_msg("%s: %s", name, err);
	assert_int_equal(fmt, want);
}

#define XML_HEAD "<?xml version=\"1.0\"?>\n<opencv_storage>\n"
#define XML_MAT(key, rows, cols, data)                                                            \
	"<" key " type_id=\"opencv-matrix\">\n  <rows>" rows "</rows>\n  <cols>" cols "</cols>\n"      \
	"  <dt>d</dt>\n  <data>\n    " data "</data></" key ">\n"

/* What the OpenCV reader read and no test showed: XML stereo files, later YAML documents. */
static void test_opencv_reader(void **state)
{
	(void)state;
	struct mvod_camera c;
	load_ok("stereo.xml", XML_HEAD XML_MAT("M1", "3", "3", "500. 0. 320. 0. 501. 240.\n 0. 0. 1.")
		XML_MAT("D1", "1", "5", "0.1 -0.2 0. 0. 0.03") XML_MAT("M2", "3", "3", "1 0 2 0 1 2 0 0 1")
		"</opencv_storage>\n", &c, MVOD_CALIB_FMT_OPENCV);
	assert_true(c.fx == 500 && c.fy == 501 && c.cx == 320 && c.cy == 240);
	assert_int_equal(c.width, 0);
	assert_int_equal(c.n_dist, 5);
	assert_true(c.dist[0] == 0.1 && c.dist[1] == -0.2 && c.dist[4] == 0.03);

	/* OpenCV reads the first document and so does mvod; the second must still be YAML. */
	load_ok("twodocs.yml", YAML_HEAD OCV_K GOOD_K OCV_D GOOD_D "---\ncamera_matrix: 7\n", &c,
		MVOD_CALIB_FMT_OPENCV);
	assert_true(c.fx == 500 && c.n_dist == 5 && c.width == 640);
	expect_error("twodocs2.yml", YAML_HEAD OCV_K GOOD_K OCV_D GOOD_D "---\n[ 1\n",
		     "YAML error at line 16"); /* the end of the text, where "]" is missing */

	struct mvod_camera fe = fisheye();
	round_trip(mvod_calib_save_opencv, "fe.xml", &fe, 4, MVOD_CALIB_FMT_OPENCV);
}

static void test_malformed_opencv_more(void **state)
{
	(void)state;
	/* 10^9 entries claimed, three given: refused from the count, with nothing sized from it. */
	expect_error("big.yml", YAML_HEAD OCV_K GOOD_K
		     "distortion_coefficients: !!opencv-matrix\n   rows: 1000000\n   cols: 1000\n   dt: d\n"
		     "   data: [ 0.1, -0.2, 0. ]\n", "not rows x cols = 1000000 x 1000");
	expect_error("big.xml", XML_HEAD XML_MAT("camera_matrix", "100000", "10000", "1 0 2 0 1 2 0 0 1")
		     "</opencv_storage>\n", "not rows x cols = 100000 x 10000");
	/* A quoted number is a string, as it is for OpenCV. */
	expect_error("quoted.yml", YAML_HEAD OCV_K "[ 500., 0., \"320\", 0., 501., 240., 0., 0., 1. ]\n"
		     OCV_D GOOD_D, "entry 2 is not a number");
	expect_error("inf.xml", XML_HEAD XML_MAT("camera_matrix", "3", "3", "1 0 2 0 1 2 0 0 inf")
		     "</opencv_storage>\n", "entry 8 is not finite");
	expect_error("rows.xml", XML_HEAD XML_MAT("camera_matrix", "3.5", "3", "1 0 2 0 1 2 0 0 1")
		     "</opencv_storage>\n", "must be a matrix");
	/* No entity is expanded and no DTD fetched: a DOCTYPE is refused outright. */
	expect_error("dtd.xml", "<?xml version=\"1.0\"?>\n<!DOCTYPE opencv_storage [<!ENTITY a \"1\">]>\n"
		     "<opencv_storage><image_width>&a;</image_width></opencv_storage>\n", "DOCTYPE");
	expect_error("bad.xml", XML_HEAD "<image_width>640</image_height>\n</opencv_storage>\n",
		     "XML error at line 3");
	/* YAML is UTF-8 (OpenCV let Latin-1 through): the byte at fault is named. */
	expect_error("latin1.yml", "%YAML:1.0\n# f\xfcr\n" OCV_K GOOD_K OCV_D GOOD_D,
		     "YAML error at byte 13: invalid leading UTF-8 octet");
	expect_error("root.xml", "<?xml version=\"1.0\"?>\n<storage></storage>\n", "<opencv_storage>");
}

/* DSO's camera.txt (JakobEngel/dso's README, "Geometric Calibration File"), each form. */
static void test_dso_reader(void **state)
{
	(void)state;
	struct mvod_camera c;
	/*
	 * TUM monoVO's form (bare relative numbers, as mono_dataset_code's FOVUndistorter reads
	 * them; these values circulate as monoVO's in public repositories), tabs and CRLF too:
	 * DSO's relative-to-pixel rule, fx w, cx w - 0.5.
	 */
	load_ok("camera.txt", "0.535719308086809 0.669566858850269 0.493248545285398 "
		"0.500408664348414 0.897966326944875\n1280 1024\ncrop\n640 480\n", &c,
		MVOD_CALIB_FMT_DSO);
	assert_int_equal(c.model, MVOD_CAM_FOV);
	assert_int_equal(c.n_dist, 1);
	assert_true(c.dist[0] == 0.897966326944875);
	assert_true(c.width == 1280 && c.height == 1024);
	assert_true(c.fx == 0.535719308086809 * 1280 && c.fy == 0.669566858850269 * 1024);
	assert_true(c.cx == 0.493248545285398 * 1280 - 0.5 && c.cy == 0.500408664348414 * 1024 - 0.5);
	load_ok("tabs.txt", "FOV\t0.5357\t0.6695\t0.4932\t0.5004\t0.8979\r\n1280 1024\r\n", &c,
		MVOD_CALIB_FMT_DSO);
	assert_true(c.model == MVOD_CAM_FOV && c.dist[0] == 0.8979 && c.cx == 0.4932 * 1280 - 0.5);
	/* In pixels (cx or cy past 1): K as it is. ATAN, PTAM's name, is the same lens. */
	load_ok("px.txt", "ATAN 685.7 685.6 631.4 512.4 0.9\n1280 1024\n", &c, MVOD_CALIB_FMT_DSO);
	assert_true(c.model == MVOD_CAM_FOV && c.fx == 685.7 && c.cx == 631.4);
	/* w = 0: DSO's pinhole; Pinhole's 5th number is that 0. */
	load_ok("pin.txt", "0.5 0.6 0.5 0.5 0\n640 480\nnone\n640 480\n\n", &c, MVOD_CALIB_FMT_DSO);
	assert_true(c.model == MVOD_CAM_PINHOLE_RADTAN && c.n_dist == 0 && c.fx == 320);
	load_ok("pin2.txt", "Pinhole 400 400 319.5 239.5 0\n640 480\n", &c, MVOD_CALIB_FMT_DSO);
	assert_true(c.n_dist == 0 && c.cx == 319.5);
	/* A principal point off the image's top-left (negative) is in pixels, not fractions. */
	load_ok("pin3.txt", "Pinhole 400 400 -5 -3 0\n640 480\n", &c, MVOD_CALIB_FMT_DSO);
	assert_true(c.fx == 400 && c.cx == -5 && c.cy == -3);
	/* RadTan (also 8 bare numbers), EquiDistant and KannalaBrandt. */
	load_ok("rt.txt", "400 400 319.5 239.5 -0.2 0.05 0.001 -0.001\n640 480\n", &c,
		MVOD_CALIB_FMT_DSO);
	assert_true(c.model == MVOD_CAM_PINHOLE_RADTAN && c.n_dist == 4 && c.dist[3] == -0.001);
	load_ok("kb.txt", "EquiDistant 400 400 319.5 239.5 0.1 -0.02 0.01 -0.002\n640 480\n"
		"400 400 319.5 239.5 0\n640 480\n", &c, MVOD_CALIB_FMT_DSO);
	assert_true(c.model == MVOD_CAM_FISHEYE_KB4 && c.n_dist == 4 && c.dist[0] == 0.1);
}

static void test_dso_malformed(void **state)
{
	(void)state;
	expect_error("d1.txt", "FOV 0.5 0.6 0.5 0.5\n640 480\n", "d1.txt line 1: \"FOV 0.5 0.6 "
		     "0.5 0.5\" is not one of DSO's lenses");
	expect_error("d2.txt", "Pinhole 0.5 0.6 0.5 0.5 0.9\n640 480\n", "d2.txt line 1:");
	expect_error("d3.txt", "FOV 0.5 0.6 0.5 0.5 0.9\n640\n", "d3.txt line 2: expected the "
		     "image size");
	expect_error("d4.txt", "FOV 0.5 0.6 0.5 0.5 0.9\n640 480\nkrop\n640 480\n",
		     "d4.txt line 3: \"krop\" is none of DSO's rectifications");
	expect_error("d5.txt", "FOV 0.5 0.6 0.5 0.5 0.9\n640 480\ncrop\n", "d5.txt line 4:");
	expect_error("d6.txt", "FOV 0.5 0.6 0.5 0.5 0.9\n640 480\ncrop\n640 480\n\nx\n",
		     "d6.txt line 6: DSO's camera.txt has 4 lines");
	expect_error("d7.txt", "FOV -0.5 0.6 0.5 0.5 0.9\n640 480\n", "d7.txt line 1: the focal "
		     "lengths must be positive");
	expect_error("d8.txt", "FOV 0.5 0.6 0.5 0.5 nan\n640 480\n", "d8.txt line 1:");
}

static struct mvod_camera fov(void)
{
	struct mvod_camera c = pinhole(0);
	c.model = MVOD_CAM_FOV;
	c.n_dist = 1;
	c.dist[0] = 0.9 / 1.1;
	return c;
}

/* The FOV lens through every writer that has a place for it; ROS has none. */
static void test_fov_round_trips(void **state)
{
	(void)state;
	struct mvod_camera c = fov();
	round_trip_within(save_mvod, "fov.json", &c, 1, MVOD_CALIB_FMT_MVOD, CJSON_REL);
	round_trip(mvod_calib_save_opencv, "fov.yml", &c, 1, MVOD_CALIB_FMT_OPENCV);
	round_trip(mvod_calib_save_opencv, "fov.xml", &c, 1, MVOD_CALIB_FMT_OPENCV);
	round_trip(mvod_calib_save_dso, "fovcam.txt", &c, 1, MVOD_CALIB_FMT_DSO);
	struct mvod_camera k = fisheye(), p = pinhole(5);
	round_trip(mvod_calib_save_dso, "kbcam.txt", &k, 4, MVOD_CALIB_FMT_DSO);
	p.dist[4] = 0; /* DSO's RadTan has k1 k2 p1 p2 */
	round_trip(mvod_calib_save_dso, "rtcam.txt", &p, 4, MVOD_CALIB_FMT_DSO);
	char err[256] = "";
	assert_int_equal(mvod_calib_save_ros(path_of("fov.yaml"), &c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "ROS camera_info has no FOV lens model"));
	assert_int_equal(mvod_calib_save_kitti(path_of("fovk.txt"), &c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "this camera has fov distortion"));
	p.dist[4] = 0.01;
	assert_int_equal(mvod_calib_save_dso(path_of("rt5.txt"), &p, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "DSO's RadTan lens has 4 coefficients"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_round_trip_mvod_opencv),
		cmocka_unit_test(test_round_trip_ros),
		cmocka_unit_test(test_kitti_writer),
		cmocka_unit_test(test_json_pair),
		cmocka_unit_test(test_malformed_pair),
		cmocka_unit_test(test_malformed_opencv),
		cmocka_unit_test(test_ros_reader),
		cmocka_unit_test(test_opencv_reader),
		cmocka_unit_test(test_malformed_opencv_more),
		cmocka_unit_test(test_dso_reader),
		cmocka_unit_test(test_dso_malformed),
		cmocka_unit_test(test_fov_round_trips),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
