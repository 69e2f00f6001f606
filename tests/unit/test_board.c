/* Board specs: every field's malformation, the geometry, the drawn pattern and its file. */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "mvod/board.h"
#include "util/image_file.h"

static void charuco_spec_round_trips(void **state)
{
	(void)state;
	struct mvod_board b;
	char err[256], back[128];
	assert_int_equal(mvod_board_parse("charuco:5x7:0.04:0.02:DICT_6X6_250", &b, err, sizeof(err)), 0);
	assert_int_equal(b.kind, MVOD_BOARD_CHARUCO);
	assert_int_equal(b.cols, 5);
	assert_int_equal(b.rows, 7);
	assert_true(b.square_m == 0.04 && b.marker_m == 0.02);
	assert_int_equal(b.dict, 10); /* cv::aruco::DICT_6X6_250 */
	assert_int_equal(mvod_board_corner_count(&b), 4 * 6);
	mvod_board_format(&b, back, sizeof(back));
	assert_string_equal(back, "charuco:5x7:0.04:0.02:DICT_6X6_250");
}

/* Indices are cv::aruco::PREDEFINED_DICTIONARY_NAME values, which the detector is handed. */
static void dictionary_table(void **state)
{
	(void)state;
	assert_int_equal(mvod_board_dict_count(), 21);
	const struct {
		const char *name;
		int index;
	} known[] = {{"DICT_4X4_50", 0}, {"DICT_6X6_250", 10}, {"DICT_7X7_1000", 15},
		     {"DICT_ARUCO_ORIGINAL", 16}, {"DICT_APRILTAG_36h11", 20}};
	for (size_t i = 0; i < sizeof(known) / sizeof(known[0]); i++)
		assert_string_equal(mvod_board_dict_name(known[i].index), known[i].name);
	assert_null(mvod_board_dict_name(21));
	assert_null(mvod_board_dict_name(-1));
	char err[256], spec[128];
	for (int k = 0; k < mvod_board_dict_count(); k++) {
		struct mvod_board b;
		snprintf(spec, sizeof(spec), "charuco:3x3:0.04:0.02:%s", mvod_board_dict_name(k));
		assert_int_equal(mvod_board_parse(spec, &b, err, sizeof(err)), 0);
		assert_int_equal(b.dict, k);
	}
	/* DICT_6X6_50 .. DICT_6X6_1000 share markers; DICT_7X7_50 and the rest do not. */
	assert_int_equal(mvod_board_dict_family(8), mvod_board_dict_family(11));
	assert_int_not_equal(mvod_board_dict_family(11), mvod_board_dict_family(12));
	assert_int_not_equal(mvod_board_dict_family(16), mvod_board_dict_family(17));
	assert_int_equal(mvod_board_dict_family_size(10), 4);
	assert_int_equal(mvod_board_dict_family_size(16), 1);
}

static void chessboard_geometry(void **state)
{
	(void)state;
	struct mvod_board b;
	char err[256];
	assert_int_equal(mvod_board_parse("chessboard:9x6:0.025", &b, err, sizeof(err)), 0);
	assert_int_equal(mvod_board_corner_count(&b), 54);
	int across, down;
	mvod_board_squares(&b, &across, &down);
	assert_int_equal(across, 10);
	assert_int_equal(down, 7);
	double p[3];
	mvod_board_corner(&b, 0, p);
	assert_true(p[0] == 0.025 && p[1] == 0.025 && p[2] == 0);
	mvod_board_corner(&b, 10, p); /* second row, second column */
	assert_true(p[0] == 0.05 && p[1] == 0.05);
}

static void malformed_specs_say_what_is_wrong(void **state)
{
	(void)state;
	static const struct {
		const char *spec, *says;
	} cases[] = {
		{"", "unknown board type"},
		{"aruco:5x7:0.04", "unknown board type"},
		{"charuco:5x7:0.04:0.02", "4 fields"},
		{"charuco:5x7:0.04:0.02:DICT_6X6_250:x", "4 fields"},
		{"charuco:5by7:0.04:0.02:DICT_6X6_250", "COLSxROWS"},
		{"charuco:1x7:0.04:0.02:DICT_6X6_250", "COLSxROWS"},
		{"charuco:5x7:-1:0.02:DICT_6X6_250", "square side"},
		{"charuco:5x7:0.04:0.05:DICT_6X6_250", "smaller than the square"},
		{"charuco:5x7:0.04:0.02:DICT_9X9_1", "unknown ArUco dictionary"},
		{"charuco:20x20:0.04:0.02:DICT_4X4_50", "use a larger dictionary"},
		{"chessboard:9x6", "2 fields"},
		{"chessboard:9x6:abc", "square side"},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		struct mvod_board b;
		char err[512] = "";
		assert_int_equal(mvod_board_parse(cases[i].spec, &b, err, sizeof(err)), -EINVAL);
		if (!strstr(err, cases[i].says))
			fail_msg("'%s': '%s' does not say '%s'", cases[i].spec, err, cases[i].says);
	}
}

/* The chessboard is drawn square by square: the top-left square black, then alternating. */
static void chessboard_drawing(void **state)
{
	(void)state;
	struct mvod_board b;
	char err[256];
	assert_int_equal(mvod_board_parse("chessboard:3x2:0.03", &b, err, sizeof(err)), 0);
	struct mvod_image img;
	assert_int_equal(mvod_board_draw(&b, 10, 5, &img), 0);
	assert_int_equal(img.w, 4 * 10 + 10);
	assert_int_equal(img.h, 3 * 10 + 10);
	assert_int_equal(img.data[0], 255);                      /* margin */
	assert_int_equal(img.data[(5 + 5) * img.stride + 5 + 5], 0);   /* square (0,0) */
	assert_int_equal(img.data[(5 + 5) * img.stride + 15 + 5], 255); /* square (1,0) */
	assert_int_equal(img.data[(15 + 5) * img.stride + 15 + 5], 0);  /* square (1,1) */
	mvod_board_image_free(&img);
}

/* A ChArUco pattern: black squares where the chessboard has them, markers inside the others. */
static void charuco_drawing(void **state)
{
	(void)state;
	struct mvod_board b;
	char err[256];
	assert_int_equal(mvod_board_parse("charuco:5x7:0.04:0.02:DICT_6X6_250", &b, err, sizeof(err)), 0);
	struct mvod_image img;
	assert_int_equal(mvod_board_draw(&b, 40, 0, &img), 0);
	assert_int_equal(img.w, 200);
	assert_int_equal(img.h, 280);
	assert_int_equal(img.data[20 * img.stride + 20], 0);  /* square (0,0): black */
	assert_int_equal(img.data[2 * img.stride + 42], 255); /* white border of square (1,0)'s marker */
	int black = 0; /* the marker in square (1,0) has black cells */
	for (int y = 50; y < 70; y++)
		for (int x = 50; x < 70; x++)
			black += img.data[(y - 40) * img.stride + x] == 0;
	assert_true(black > 0);
	mvod_board_image_free(&img);
	assert_int_equal(mvod_board_draw(&b, 2, 0, &img), -EINVAL);
}

static long file_size(const char *path)
{
	struct stat st;
	return stat(path, &st) ? -1 : (long)st.st_size;
}

/*
 * The board's writer: with a resolution, pHYs says it in pixels per metre (300 dpi = 11811);
 * a request it refuses or an encoder that fails leaves the file written before as it was.
 */
static void image_file_writes_whole_or_not_at_all(void **state)
{
	(void)state;
	char dir[] = "/tmp/mvod-test-board-XXXXXX", path[64], err[256];
	assert_non_null(mkdtemp(dir));
	snprintf(path, sizeof(path), "%s/board.png", dir);
	struct mvod_board b;
	struct mvod_image img;
	assert_int_equal(mvod_board_parse("chessboard:3x2:0.03", &b, err, sizeof(err)), 0);
	assert_int_equal(mvod_board_draw(&b, 10, 5, &img), 0);
	assert_int_equal(mvod_image_file_write(path, ".png", &img, 300), 0);
	unsigned char head[64];
	FILE *f = fopen(path, "rb");
	assert_non_null(f);
	assert_int_equal(fread(head, 1, sizeof(head), f), sizeof(head));
	fclose(f);
	/* Signature 8 + IHDR 25, then pHYs: length 9, type, x and y pixels per metre, unit 1. */
	static const unsigned char phys[] = {0, 0, 0, 9, 'p', 'H', 'Y', 's', 0, 0, 0x2e, 0x23,
					     0, 0, 0x2e, 0x23, 1};
	assert_memory_equal(head + 33, phys, sizeof(phys));
	long good = file_size(path);
	assert_int_equal(mvod_image_file_write(path, ".jpg", &img, 300), -EINVAL);
	assert_int_equal(mvod_image_file_write(path, ".png", &img, -1), -EINVAL);
	assert_int_equal(mvod_image_file_write(path, ".nosuchformat", &img, 0), -EIO);
	assert_int_equal(file_size(path), good);
	mvod_board_image_free(&img);
	assert_int_equal(unlink(path), 0);
	assert_int_equal(rmdir(dir), 0); /* fails if a temporary was left beside the file */
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(charuco_spec_round_trips),
		cmocka_unit_test(dictionary_table),
		cmocka_unit_test(chessboard_geometry),
		cmocka_unit_test(malformed_specs_say_what_is_wrong),
		cmocka_unit_test(chessboard_drawing),
		cmocka_unit_test(charuco_drawing),
		cmocka_unit_test(image_file_writes_whole_or_not_at_all),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
