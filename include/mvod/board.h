/* Calibration targets: the board spec users type, its geometry, and its printable image. */
#ifndef MVOD_BOARD_H
#define MVOD_BOARD_H

#include <stddef.h>

#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

enum mvod_board_kind {
	MVOD_BOARD_CHARUCO = 0,    /* chessboard with ArUco markers in the white squares */
	MVOD_BOARD_CHESSBOARD = 1, /* plain chessboard */
};

/*
 * "charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT" (COLS x ROWS squares) or
 * "chessboard:COLSxROWS:SQUARE_M" (COLS x ROWS inner corners).
 */
struct mvod_board {
	enum mvod_board_kind kind;
	int cols, rows;        /* charuco: squares; chessboard: inner corners */
	double square_m;       /* side of a square, metres */
	double marker_m;       /* side of a marker, metres (charuco; < square_m) */
	int dict;              /* cv::aruco::PREDEFINED_DICTIONARY_NAME (charuco) */
	char dict_name[32];    /* e.g. "DICT_6X6_250" */
};

/*
 * The ArUco dictionaries a spec may name, in cv::aruco::PREDEFINED_DICTIONARY_NAME order
 * (struct mvod_board's dict): how many, and each one's name, e.g. "DICT_6X6_250" (NULL when
 * dict is out of range).
 */
int mvod_board_dict_count(void);
const char *mvod_board_dict_name(int dict);
/*
 * Dictionaries of one family share their markers (DICT_6X6_50 is DICT_6X6_250's first 50):
 * the family's number, equal for all its members, and how many dictionaries it has (1 for
 * one that shares with none).
 */
int mvod_board_dict_family(int dict);
int mvod_board_dict_family_size(int dict);

/* Parses a spec; on failure returns -EINVAL and says in err what is wrong and what is expected. */
int mvod_board_parse(const char *spec, struct mvod_board *b, char *err, size_t errlen);
/* The spec back, as mvod_board_parse reads it. */
void mvod_board_format(const struct mvod_board *b, char *buf, size_t len);

/* Interior corners (those calibration uses): charuco (cols-1)(rows-1), chessboard cols*rows. */
int mvod_board_corner_count(const struct mvod_board *b);
/* Squares across and down the printed pattern: charuco cols x rows, chessboard (cols+1) x (rows+1). */
void mvod_board_squares(const struct mvod_board *b, int *across, int *down);

/*
 * Board frame: origin at the pattern's top-left outer corner, x right, y down (along the
 * printed rows), z into the board; metres. Corner i (row-major over the interior corners,
 * OpenCV's charuco and chessboard order) lies at ((i % nx) + 1, (i / nx) + 1) * square_m, z 0,
 * with nx interior corners per row.
 */
void mvod_board_corner(const struct mvod_board *b, int i, double xyz[3]);

/*
 * Draws the pattern with px_per_square pixels per square and a white quiet zone of margin_px
 * on every side, as an 8-bit grey image. out->data is malloc'ed and owned by the caller
 * (free it with mvod_board_image_free). Returns 0 or -errno.
 */
int mvod_board_draw(const struct mvod_board *b, int px_per_square, int margin_px,
		    struct mvod_image *out);
void mvod_board_image_free(struct mvod_image *img);
/*
 * Writes text (one line, ASCII) in grey, centred in the bottom quiet zone of a board image
 * drawn with margin_px, at most a third of the zone tall and clear of the pattern, so the
 * printed sheet names its spec. Returns 0 or -errno (-EINVAL: no room for it).
 */
int mvod_board_caption(struct mvod_image *img, int margin_px, const char *text);

#ifdef __cplusplus
}
#endif

#endif
