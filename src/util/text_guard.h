/*
 * The guard every parse of structured text (YAML through libyaml, XML through libxml2, JSON
 * through cJSON) passes first: a scan that bounds what makes those parsers slow. libyaml's
 * cost grows with the square of the nesting depth (a 1 MiB sensor.yaml of nested sequences
 * parsed for over 13 minutes; 1000 levels 0.008 s, 4000 levels 0.05 s) and of the number
 * of anchors (1024 in 4 MiB: 0.9 s to load, 256: 0.23 s); libxml2's
 * with the square of one element's attributes (2000: 1.9 s, 256: 0.26 s). Measured on the
 * project's 2-core x86: the worst 4 MiB YAML within these bounds, 64 levels throughout,
 * costs 0.6 s here and 0.7 s in libyaml's load, a flat one 0.2 s; XML and JSON 0.01 s here.
 *
 *   ret = mvod_text_guard(text, len, MVOD_TEXT_YAML, err, errlen);
 *   if (ret) ... "PATH: " err     // the reason names the line; the caller names the file
 */
#ifndef MVOD_TEXT_GUARD_H
#define MVOD_TEXT_GUARD_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

enum mvod_text_syntax {
	MVOD_TEXT_YAML,
	MVOD_TEXT_XML,
	MVOD_TEXT_JSON,
};

/*
 * Nesting levels a text may have. Camera files nest 3 (OpenCV's matrices in YAML, XML or
 * JSON), EuRoC's sensor.yaml 3; the YAML count is an upper bound of libyaml's (two levels per
 * indentation step, a block sequence may sit at its key's indentation).
 */
#define MVOD_TEXT_MAX_DEPTH 64
/* Anchors and aliases in a YAML text, and attributes of one XML element; none uses any. */
#define MVOD_TEXT_MAX_NAMES 256
/* Bytes of a structured text: the calibration files' bound, 4 MiB. */
#define MVOD_TEXT_MAX_BYTES ((size_t)4 << 20)

/*
 * Checks text[0, len) as syntax against the bounds above before it is parsed. Returns 0, or
 * -EFBIG (larger than MVOD_TEXT_MAX_BYTES) or -ELOOP (nested deeper, or too many names) with
 * a one-line reason naming the line in err. Does not validate: what passes may still be no
 * YAML, XML or JSON, for the parser to say.
 */
int mvod_text_guard(const char *text, size_t len, enum mvod_text_syntax syntax, char *err,
		    size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
