/*
 * OpenCV-flavoured YAML, read with libyaml: the one path for calibration files (calib/) and
 * EuRoC's sensor.yaml (capture/). What makes it OpenCV's: the "%YAML:1.0" line OpenCV writes
 * (no YAML 1.1 directive: libyaml stops at it, so it is read as a comment), matrices as a map
 * of rows, cols and data (OpenCV's !!opencv-matrix with its dt, ROS's and EuRoC's T_BS alike),
 * and the number rules OpenCV's XML shares (mvod_cvyaml_take).
 */
#ifndef MVOD_UTIL_CVYAML_H
#define MVOD_UTIL_CVYAML_H

#include <stdbool.h>
#include <stddef.h>

#include <yaml.h>

/* The entries of a number list: all counted, the first cap of them kept in v (caller's). */
struct mvod_cvyaml_numbers {
	double *v;
	size_t cap;
	size_t count;
	size_t bad;         /* index of the first entry that is no finite number, or SIZE_MAX */
	bool bad_is_number; /* that entry is a number, only not a finite one */
};

/* An empty list keeping up to cap entries in v. */
struct mvod_cvyaml_numbers mvod_cvyaml_numbers_into(double *v, size_t cap);

/*
 * The first YAML document of text into doc (yaml_document_delete when done). A first line
 * "%YAML:1.0" (after a UTF-8 byte order mark and blank lines) is read as a comment, so line
 * numbers stay right. Later documents are parsed, so that a syntax error anywhere is one (as
 * it is for OpenCV), but not kept. The text passes util/text_guard.h's bounds first (-EFBIG,
 * -ELOOP with its reason in why). -EINVAL with "YAML error at line N: PROBLEM" (or "at byte
 * N" for bad UTF-8, which libyaml marks by byte) in why; -ENOMEM.
 */
int mvod_cvyaml_load(const char *text, yaml_document_t *doc, char *why, size_t whylen);

/* The value under key in map (the first, if the key repeats), or NULL. */
yaml_node_t *mvod_cvyaml_child(yaml_document_t *doc, const yaml_node_t *map, const char *key);

/* The 1-based line where n starts. */
size_t mvod_cvyaml_line(const yaml_node_t *n);

/* One entry of len bytes at s (NUL-terminated there), or s NULL for one that is no scalar. */
void mvod_cvyaml_take(struct mvod_cvyaml_numbers *m, const char *s, size_t len);

/* seq, a sequence of plain scalars, into m (counted from empty); -EINVAL for another node. */
int mvod_cvyaml_sequence(yaml_document_t *doc, const yaml_node_t *seq,
			 struct mvod_cvyaml_numbers *m);

/*
 * Whether m holds a rows x cols matrix of finite numbers: 0, or -EINVAL with what is wrong in
 * why ("data holds 15 numbers, not rows x cols = 4 x 4", "entry 3 is not finite").
 */
int mvod_cvyaml_matrix_check(int rows, int cols, const struct mvod_cvyaml_numbers *m, char *why,
			     size_t whylen);

/*
 * A matrix node: a map of rows, cols (whole numbers) and data (rows * cols finite numbers),
 * into *rows, *cols and m. Nothing is sized from rows and cols, so a file that claims a
 * billion entries costs no more than its text. -EINVAL with the reason in why and the line
 * of the node at fault (the map, or its data) in *line.
 */
int mvod_cvyaml_matrix(yaml_document_t *doc, const yaml_node_t *map, int *rows, int *cols,
		       struct mvod_cvyaml_numbers *m, size_t *line, char *why, size_t whylen);

#endif
