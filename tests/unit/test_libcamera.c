/*
 * The libcamera: backend's logic that needs no camera: its URI (id or index, parameters) and
 * the mapping between mvod's camera formats and libcamera's DRM fourccs. Opening libcamera:0
 * on a machine without a camera fails with a clear message (skipped without libcamera).
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "capture/libcamera_shim.h"
#include "capture/v4l2.h"
#include "mvod/capture.h"

static void test_index_and_params(void **state)
{
	(void)state;
	struct mvod_lcam_want w;
	char err[256] = "";
	assert_int_equal(mvod_lcam_parse("1?width=640&height=480&format=nv12", &w, err,
					 sizeof(err)), 0);
	assert_string_equal(w.id, "");
	assert_int_equal(w.index, 1);
	assert_int_equal(w.width, 640);
	assert_int_equal(w.height, 480);
	assert_int_equal(w.format, MVOD_CAMFMT_NV12);
}

static void test_id(void **state)
{
	(void)state;
	struct mvod_lcam_want w;
	char err[256] = "";
	assert_int_equal(mvod_lcam_parse("/base/soc/i2c0mux/i2c@1/imx219@10", &w, err,
					 sizeof(err)), 0);
	assert_string_equal(w.id, "/base/soc/i2c0mux/i2c@1/imx219@10");
	assert_int_equal(w.width, 0);
	assert_int_equal(w.format, -1);
}

static void expect_bad(const char *location, const char *needle)
{
	struct mvod_lcam_want w;
	char err[256] = "";
	assert_int_equal(mvod_lcam_parse(location, &w, err, sizeof(err)), -EINVAL);
	if (!strstr(err, needle))
		fail_msg("\"%s\" does not say \"%s\"", err, needle);
}

static void test_bad_uris(void **state)
{
	(void)state;
	expect_bad("", "needs a camera id or index");
	expect_bad("0?width=abc", "width=abc: expected an integer");
	expect_bad("0?format=RGB3", "format=RGB3: expected one of GREY, YUYV, NV12, MJPEG");
	expect_bad("0?fps=30", "unknown source parameter \"fps\"");
	expect_bad("0?width", "\"width\" in the source URI is not key=value");
	expect_bad("99", "index=99: expected an integer in [0, 63]");
}

/* The DRM fourccs libcamera names its formats by (include/linux/drm_fourcc.h). */
static void test_formats(void **state)
{
	(void)state;
	static const struct {
		enum mvod_camfmt f;
		const char code[5];
	} map[] = {
		{MVOD_CAMFMT_GREY, "R8  "},
		{MVOD_CAMFMT_YUYV, "YUYV"},
		{MVOD_CAMFMT_NV12, "NV12"},
		{MVOD_CAMFMT_MJPEG, "MJPG"},
	};
	for (size_t i = 0; i < sizeof(map) / sizeof(map[0]); i++) {
		uint32_t cc;
		memcpy(&cc, map[i].code, 4);
		assert_int_equal(mvod_camfmt_fourcc(map[i].f, MVOD_CAMFMT_LIBCAMERA), cc);
		enum mvod_camfmt back;
		assert_int_equal(mvod_camfmt_of_fourcc(cc, MVOD_CAMFMT_LIBCAMERA, &back), 0);
		assert_int_equal(back, map[i].f);
	}
	enum mvod_camfmt f;
	assert_int_equal(mvod_camfmt_of_fourcc(0x34325842 /* XB24 */, MVOD_CAMFMT_LIBCAMERA, &f),
			 -ENOENT);
}

/* V4L2 through its syscall seam (capture/v4l2.h) with no node: no /dev/video* at all. */
static int no_node(const char *path, int flags)
{
	(void)path, (void)flags;
	errno = ENOENT;
	return -1;
}

/*
 * mvod --list-cameras with no V4L2 camera: a build without libcamera says the backend is not
 * built and how to get it; it said "and no libcamera camera", as if libcamera had looked.
 */
static void test_list_none(void **state)
{
	(void)state;
	static const struct mvod_v4l2_io none = {.open = no_node};
	const struct mvod_v4l2_io *kernel = mvod_v4l2_io;
	mvod_v4l2_io = &none;
	char *text = NULL;
	size_t len = 0;
	FILE *out = open_memstream(&text, &len);
	int n = mvod_capture_list_cameras(out);
	fclose(out);
	mvod_v4l2_io = kernel;
#if MVOD_HAVE_LIBCAMERA
	if (n > 0) /* a libcamera camera is attached */
		skip();
	assert_string_equal(text, "No cameras found: no V4L2 capture device in /dev/video*, and no "
				  "libcamera camera.\n");
#else
	assert_int_equal(n, 0);
	assert_string_equal(text, "No cameras found: no V4L2 capture device in /dev/video*; "
				  "libcamera cameras cannot be listed: this mvod was built without "
				  "libcamera: install libcamera-dev and rebuild (meson setup "
				  "-Dlibcamera=enabled)\n");
#endif
	free(text);
}

/* This machine has no camera: either libcamera finds none, or mvod was built without it. */
static void test_no_camera(void **state)
{
	(void)state;
	struct mvod_source *src = NULL;
	char err[512] = "";
	int ret = mvod_source_open("libcamera:0", &src, err, sizeof(err));
	if (ret == 0) {
		mvod_source_close(src);
		skip();
	}
	assert_null(src);
	if (!strstr(err, "no libcamera camera 0") && !strstr(err, "built without libcamera"))
		fail_msg("unclear: %s", err);
}

int main(void)
{
	setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0); /* its INFO lines say nothing to a test */
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_index_and_params),
		cmocka_unit_test(test_id),
		cmocka_unit_test(test_bad_uris),
		cmocka_unit_test(test_formats),
		cmocka_unit_test(test_no_camera),
		cmocka_unit_test(test_list_none),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
