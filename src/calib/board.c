/* Board specs: parsing, formatting and geometry. Drawing is in board_shim.cpp. */
#include "mvod/board.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/errbuf.h"

/* cv::aruco::PREDEFINED_DICTIONARY_NAME, in its order, with each dictionary's marker count. */
static const struct {
	const char *name;
	int markers;
} dicts[] = {
	{"DICT_4X4_50", 50},   {"DICT_4X4_100", 100},   {"DICT_4X4_250", 250},
	{"DICT_4X4_1000", 1000}, {"DICT_5X5_50", 50},     {"DICT_5X5_100", 100},
	{"DICT_5X5_250", 250}, {"DICT_5X5_1000", 1000}, {"DICT_6X6_50", 50},
	{"DICT_6X6_100", 100}, {"DICT_6X6_250", 250},   {"DICT_6X6_1000", 1000},
	{"DICT_7X7_50", 50},   {"DICT_7X7_100", 100},   {"DICT_7X7_250", 250},
	{"DICT_7X7_1000", 1000}, {"DICT_ARUCO_ORIGINAL", 1024}, {"DICT_APRILTAG_16h5", 30},
	{"DICT_APRILTAG_25h9", 35}, {"DICT_APRILTAG_36h10", 2320}, {"DICT_APRILTAG_36h11", 587},
};
#define N_DICTS ((int)(sizeof(dicts) / sizeof(dicts[0])))
/* The first 16 come in families of four sizes (50, 100, 250, 1000 markers of one code). */
#define N_SIZED_DICTS 16
#define DICT_FAMILY_SIZE 4

#define CHARUCO_USAGE "charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT, e.g. charuco:5x7:0.04:0.02:DICT_6X6_250"
#define CHESS_USAGE "chessboard:COLSxROWS:SQUARE_M (inner corners), e.g. chessboard:9x6:0.025"

static int parse_size(const char *s, int *cols, int *rows)
{
	char *end;
	long c = strtol(s, &end, 10);
	if (end == s || (*end != 'x' && *end != 'X'))
		return -EINVAL;
	const char *r0 = end + 1;
	long r = strtol(r0, &end, 10);
	if (end == r0 || *end || c < 2 || r < 2 || c > 100 || r > 100)
		return -EINVAL;
	*cols = (int)c;
	*rows = (int)r;
	return 0;
}

static int parse_length(const char *s, double *out)
{
	char *end;
	double v = strtod(s, &end);
	if (end == s || *end || !isfinite(v) || v <= 0 || v > 10)
		return -EINVAL;
	*out = v;
	return 0;
}

static int parse_dict(const char *s, struct mvod_board *b)
{
	for (int i = 0; i < N_DICTS; i++) {
		if (strcasecmp(s, dicts[i].name) == 0) {
			b->dict = i;
			snprintf(b->dict_name, sizeof(b->dict_name), "%s", dicts[i].name);
			return 0;
		}
	}
	return -EINVAL;
}

/* Splits spec at ':' into at most max fields, in place in buf. Returns the field count. */
static int split(char *buf, char **fields, int max)
{
	int n = 0;
	for (char *p = buf; n < max; n++) {
		fields[n] = p;
		p = strchr(p, ':');
		if (!p)
			return n + 1;
		*p++ = '\0';
	}
	return max + 1; /* too many */
}

static int parse_charuco(char **f, int n, struct mvod_board *b, char *err, size_t errlen)
{
	if (n != 5)
		return mvod_errf(err, errlen, -EINVAL, "a ChArUco board needs 4 fields after 'charuco:': " CHARUCO_USAGE);
	if (parse_size(f[1], &b->cols, &b->rows))
		return mvod_errf(err, errlen, -EINVAL, "'%s': squares must be COLSxROWS, each 2..100", f[1]);
	if (parse_length(f[2], &b->square_m))
		return mvod_errf(err, errlen, -EINVAL, "'%s': the square side must be a length in metres, e.g. 0.04", f[2]);
	if (parse_length(f[3], &b->marker_m) || b->marker_m >= b->square_m)
		return mvod_errf(err, errlen, -EINVAL,
				 "'%s': the marker side must be a length in metres smaller than the square (%g)",
				 f[3], b->square_m);
	if (parse_dict(f[4], b)) {
		char names[512] = "";
		for (int i = 0; i < N_DICTS; i++)
			snprintf(names + strlen(names), sizeof(names) - strlen(names), "%s%s",
				 i ? " " : "", dicts[i].name);
		return mvod_errf(err, errlen, -EINVAL, "'%s': unknown ArUco dictionary; one of: %s", f[4], names);
	}
	int markers = b->cols * b->rows / 2;
	if (markers > dicts[b->dict].markers)
		return mvod_errf(err, errlen, -EINVAL,
				 "a %dx%d ChArUco board has %d markers but %s has only %d; use a larger dictionary",
				 b->cols, b->rows, markers, b->dict_name, dicts[b->dict].markers);
	return 0;
}

int mvod_board_parse(const char *spec, struct mvod_board *b, char *err, size_t errlen)
{
	memset(b, 0, sizeof(*b));
	char buf[256];
	if (!spec || strlen(spec) >= sizeof(buf))
		return mvod_errf(err, errlen, -EINVAL, "expected " CHARUCO_USAGE " or " CHESS_USAGE);
	snprintf(buf, sizeof(buf), "%s", spec);
	char *f[6];
	int n = split(buf, f, 5);
	if (strcmp(f[0], "charuco") == 0) {
		b->kind = MVOD_BOARD_CHARUCO;
		return parse_charuco(f, n, b, err, errlen);
	}
	if (strcmp(f[0], "chessboard") == 0) {
		b->kind = MVOD_BOARD_CHESSBOARD;
		if (n != 3)
			return mvod_errf(err, errlen, -EINVAL, "a chessboard needs 2 fields after 'chessboard:': " CHESS_USAGE);
		if (parse_size(f[1], &b->cols, &b->rows))
			return mvod_errf(err, errlen, -EINVAL, "'%s': inner corners must be COLSxROWS, each 2..100", f[1]);
		if (parse_length(f[2], &b->square_m))
			return mvod_errf(err, errlen, -EINVAL, "'%s': the square side must be a length in metres, e.g. 0.025", f[2]);
		return 0;
	}
	return mvod_errf(err, errlen, -EINVAL, "unknown board type '%s'; expected " CHARUCO_USAGE " or " CHESS_USAGE, f[0]);
}

void mvod_board_format(const struct mvod_board *b, char *buf, size_t len)
{
	if (b->kind == MVOD_BOARD_CHARUCO)
		snprintf(buf, len, "charuco:%dx%d:%g:%g:%s", b->cols, b->rows, b->square_m, b->marker_m,
			 b->dict_name);
	else
		snprintf(buf, len, "chessboard:%dx%d:%g", b->cols, b->rows, b->square_m);
}

static int corners_across(const struct mvod_board *b)
{
	return b->kind == MVOD_BOARD_CHARUCO ? b->cols - 1 : b->cols;
}

int mvod_board_corner_count(const struct mvod_board *b)
{
	int down = b->kind == MVOD_BOARD_CHARUCO ? b->rows - 1 : b->rows;
	return corners_across(b) * down;
}

void mvod_board_squares(const struct mvod_board *b, int *across, int *down)
{
	int extra = b->kind == MVOD_BOARD_CHARUCO ? 0 : 1;
	*across = b->cols + extra;
	*down = b->rows + extra;
}

void mvod_board_corner(const struct mvod_board *b, int i, double xyz[3])
{
	int nx = corners_across(b);
	xyz[0] = (i % nx + 1) * b->square_m;
	xyz[1] = (i / nx + 1) * b->square_m;
	xyz[2] = 0;
}

int mvod_board_dict_count(void)
{
	return N_DICTS;
}

const char *mvod_board_dict_name(int dict)
{
	return dict >= 0 && dict < N_DICTS ? dicts[dict].name : NULL;
}

int mvod_board_dict_family(int dict)
{
	return dict < N_SIZED_DICTS ? dict / DICT_FAMILY_SIZE : dict;
}

int mvod_board_dict_family_size(int dict)
{
	return dict < N_SIZED_DICTS ? DICT_FAMILY_SIZE : 1;
}
