/*
 * The structured-text guard (util/text_guard.h): camera files as OpenCV, ROS and mvod write
 * them pass; one nesting level, anchor or attribute past the bounds is refused with its line,
 * in every syntax and every way of nesting; strings, comments and CDATA do not count.
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "util/text_guard.h"

static int guard(const char *text, enum mvod_text_syntax syntax, char *err, size_t errlen)
{
	return mvod_text_guard(text, strlen(text), syntax, err, errlen);
}

static void expect_ok(const char *text, enum mvod_text_syntax syntax)
{
	char err[256] = "";
	if (guard(text, syntax, err, sizeof(err)))
		fail_msg("refused: %s\n%s", err, text);
}

static void expect_refused(const char *text, enum mvod_text_syntax syntax, const char *needle)
{
	char err[256] = "";
	assert_int_equal(guard(text, syntax, err, sizeof(err)), -ELOOP);
	if (!strstr(err, needle))
		fail_msg("\"%s\" lacks \"%s\"", err, needle);
}

/* The files mvod reads, as their writers write them. */
static void test_camera_files(void **state)
{
	(void)state;
	expect_ok("%YAML 1.0\n---\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
		  "   data: [ 452.5, 0., 317.7, 0., 456.8, 277.8, 0., 0., 1. ]\n"
		  "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
		  "   data: [ 0.1, -0.2, 0., 0., 0. ]\n", MVOD_TEXT_YAML);
	expect_ok("image_width: 640\nimage_height: 480\ncamera_name: 'narrow_stereo'\n"
		  "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [452.5, 0, 317.7, 0, 456.8, 277.8, 0, "
		  "0, 1]\ndistortion_model: plumb_bob\n", MVOD_TEXT_YAML);
	expect_ok("sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [0.0148655429818, "
		  "-0.999880929698, 0.00414029679422, -0.0216401454975,\n         0.999557249008, "
		  "0.0149672133247, 0.025715529948, -0.064676986768,\n         0, 0, 0, 1]\n"
		  "intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv\n", MVOD_TEXT_YAML);
	expect_ok("<?xml version=\"1.0\"?>\n<opencv_storage>\n<camera_matrix type_id=\"opencv-matrix\">"
		  "\n  <rows>3</rows>\n  <cols>3</cols>\n  <dt>d</dt>\n  <data>\n    452.5 0. 317.7 0. "
		  "456.8 277.8 0. 0. 1.</data></camera_matrix>\n</opencv_storage>\n", MVOD_TEXT_XML);
	expect_ok("{\n\t\"format\":\t\"mvod-calibration/1\",\n\t\"K\":\t[[452.5, 0, 317.7], [0, 456.8, "
		  "277.8], [0, 0, 1]],\n\t\"mount\":\t{\"height_m\": 1.5}\n}", MVOD_TEXT_JSON);
}

/* depth levels of open, a leaf, depth of close, in a static buffer. */
static const char *nested(int depth, const char *open, const char *leaf, const char *close)
{
	static char buf[16384];
	size_t k = 0;
	for (int i = 0; i < depth; i++)
		k += (size_t)snprintf(buf + k, sizeof(buf) - k, "%s", open);
	k += (size_t)snprintf(buf + k, sizeof(buf) - k, "%s", leaf);
	for (int i = 0; i < depth; i++)
		k += (size_t)snprintf(buf + k, sizeof(buf) - k, "%s", close);
	return buf;
}

/* Every way each syntax nests: MVOD_TEXT_MAX_DEPTH levels pass, one more is refused. */
static void test_depth(void **state)
{
	(void)state;
	const int max = MVOD_TEXT_MAX_DEPTH;
	static const struct {
		enum mvod_text_syntax syntax;
		const char *open, *leaf, *close;
	} ways[] = {
		{MVOD_TEXT_YAML, "[", "1", "]"},
		{MVOD_TEXT_YAML, "{a: ", "1", "}"},
		{MVOD_TEXT_YAML, "- ", "x", ""},
		{MVOD_TEXT_XML, "<a>", "1", "</a>"},
		{MVOD_TEXT_XML, "<a b='>'>", "1", "</a>"}, /* a '>' in a value ends no tag */
		{MVOD_TEXT_JSON, "[", "1", "]"},
		{MVOD_TEXT_JSON, "{\"a\":", "1", "}"},
	};
	for (size_t i = 0; i < sizeof(ways) / sizeof(ways[0]); i++) {
		expect_ok(nested(max, ways[i].open, ways[i].leaf, ways[i].close), ways[i].syntax);
		expect_refused(nested(max + 1, ways[i].open, ways[i].leaf, ways[i].close),
			       ways[i].syntax, "line 1: nested more than 64 levels deep");
	}
	/* YAML's block mappings, by indentation, each on its line: the line is named. */
	char text[16384];
	size_t k = 0;
	for (int i = 0; i <= max; i++)
		k += (size_t)snprintf(text + k, sizeof(text) - k, "%*sk:\n", i, "");
	snprintf(text + k, sizeof(text) - k, "%*sx\n", max + 1, "");
	expect_refused(text, MVOD_TEXT_YAML, "line 65: nested more than 64 levels deep");
}

/* Brackets in strings, comments and CDATA are no nesting; a closing one there ends none. */
static void test_quoted(void **state)
{
	(void)state;
	char text[32768];
	snprintf(text, sizeof(text), "[\"]]]]]]]]\\\"]]]\", %s]", nested(64, "[", "1", "]"));
	expect_refused(text, MVOD_TEXT_JSON, "nested more than 64");
	snprintf(text, sizeof(text), "{\"a\": \"%s\"}", nested(100, "[", "", ""));
	expect_ok(text, MVOD_TEXT_JSON);
	snprintf(text, sizeof(text), "<r><!-- </a></a> --><![CDATA[</a></a>]]>%s</r>",
		 nested(64, "<a>", "", "</a>"));
	expect_refused(text, MVOD_TEXT_XML, "nested more than 64");
	snprintf(text, sizeof(text), "<r><!-- <a><a><a> --><![CDATA[<a><a>]]><?pi <a>?>%s</r>",
		 nested(63, "<a>", "", "</a>"));
	expect_ok(text, MVOD_TEXT_XML);
	snprintf(text, sizeof(text), "a: \"[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[["
		 "[[[[[[[[[[[[[[[[\" # [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\n"
		 "b: |\n  [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\n");
	expect_ok(text, MVOD_TEXT_YAML);
}

/* Anchors and aliases (libyaml searches every anchor before for each), XML attributes. */
static void test_names(void **state)
{
	(void)state;
	static char text[65536];
	for (int extra = 0; extra < 2; extra++) {
		size_t k = (size_t)snprintf(text, sizeof(text), "[&a x");
		for (int i = 1; i < MVOD_TEXT_MAX_NAMES + extra; i++)
			k += (size_t)snprintf(text + k, sizeof(text) - k, ", *a");
		snprintf(text + k, sizeof(text) - k, "]");
		if (extra)
			expect_refused(text, MVOD_TEXT_YAML, "line 1: more than 256 anchors and aliases");
		else
			expect_ok(text, MVOD_TEXT_YAML);
		k = (size_t)snprintf(text, sizeof(text), "<r>\n<e");
		for (int i = 0; i < MVOD_TEXT_MAX_NAMES + extra; i++)
			k += (size_t)snprintf(text + k, sizeof(text) - k, " a%d=\"=\"", i);
		snprintf(text + k, sizeof(text) - k, "/></r>");
		if (extra)
			expect_refused(text, MVOD_TEXT_XML, "line 2: more than 256 attributes in one "
				       "element");
		else
			expect_ok(text, MVOD_TEXT_XML);
	}
}

/* A file over the bound is refused by its length, before a byte is scanned. */
static void test_size(void **state)
{
	(void)state;
	char err[256] = "", *text = malloc(MVOD_TEXT_MAX_BYTES + 1);
	assert_non_null(text);
	memset(text, ' ', MVOD_TEXT_MAX_BYTES + 1);
	assert_int_equal(mvod_text_guard(text, MVOD_TEXT_MAX_BYTES, MVOD_TEXT_JSON, err,
					 sizeof(err)), 0);
	assert_int_equal(mvod_text_guard(text, MVOD_TEXT_MAX_BYTES + 1, MVOD_TEXT_JSON, err,
					 sizeof(err)), -EFBIG);
	free(text);
	assert_non_null(strstr(err, "4194305 bytes, more than the 4194304 of any camera file"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_camera_files),
		cmocka_unit_test(test_depth),
		cmocka_unit_test(test_quoted),
		cmocka_unit_test(test_names),
		cmocka_unit_test(test_size),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
