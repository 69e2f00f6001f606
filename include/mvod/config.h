/*
 * mvod's settings: one table of keys drives the INI file (/etc/mvod/mvod.conf, libinih), the
 * command-line flags of `mvod run`, `mvod --print-config`, and the option reference (--help,
 * --help-all, the man page mvod(1)), so none can drift from another. A second table holds the
 * command line's options that are no setting (--config, --help, ...), for the parser and the
 * reference alike.
 */
#ifndef MVOD_CONFIG_H
#define MVOD_CONFIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "mvod/log.h"
#include "mvod/pipeline.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Everything `mvod run` is told. Strings are either borrowed (defaults, argv) or owned (read
 * from a file); mvod_config_fini frees the owned ones, so a config is not to be copied by value.
 */
struct mvod_config {
	struct mvod_run_opts run;
	const char *lcm_url;        /* NULL: $LCM_DEFAULT_URL, then LCM's default */
	const char *pose_channel;   /* MVOD_POSE */
	const char *status_channel; /* MVOD_STATUS */
	bool lcm_enabled;           /* true */
	enum mvod_log_level log_level; /* info */
	bool quiet;                 /* warnings and errors only, no summary. false */
	uint64_t set;               /* bit i: mvod_config_keys[i] was given (file or flag) */
	uint64_t owned;             /* bit i: the string of key i is ours to free */
};

enum mvod_config_type {
	MVOD_CONFIG_STRING,
	MVOD_CONFIG_INT,    /* int */
	MVOD_CONFIG_INT64,  /* int64_t */
	MVOD_CONFIG_DOUBLE,
	MVOD_CONFIG_BOOL,   /* bool; its flag takes no value and sets flag_value */
	MVOD_CONFIG_ENUM,   /* an enum whose values are the indices of choices */
};

/* One setting: where it lives in the file, its flag, its type and range, its field. */
struct mvod_config_key {
	const char *section, *key; /* INI */
	const char *flag;          /* long option, without "--" */
	char short_flag;           /* or 0 */
	enum mvod_config_type type;
	size_t offset;             /* of the field in struct mvod_config */
	double lo, hi;             /* numbers: the accepted range; strings: hi > 0 = longest */
	bool odd;                  /* ints: odd, or 0 (kernel sizes) */
	bool optional;             /* strings: empty means none (NULL) */
	bool flag_value;           /* bools: what the flag sets */
	bool run_only;             /* only mvod run uses it (LCM): mvod bench refuses its flag */
	/*
	 * Unless given, mvod_config_finish derives it from other keys (the trajectory format from
	 * the trajectory's name): --print-config then writes it as a comment, so that a file made
	 * from the printout keeps following them when they are edited.
	 */
	bool derived;
	const char *const *choices; /* enums, NULL-terminated, in enum order */
	/* strings: what a value must be beyond its length: 0, or -EINVAL with what it takes */
	int (*check)(const char *text, char *err, size_t errlen);
	/*
	 * The reference: the flag's value as named there ("N", "FILE"; NULL for an enum, whose
	 * choices name it, and a bool), a one-line summary (--help), the rest (--help-all and
	 * mvod(1), after the summary; may be NULL), and what the default means where the value
	 * alone does not say it (an empty string's, a derived key's; NULL: the value, "none").
	 */
	const char *arg, *summary, *help, *dflt;
};

extern const struct mvod_config_key mvod_config_keys[];
extern const int mvod_config_nkeys;

/* The command line's options that are no setting, by index into mvod_config_flags. */
enum mvod_config_flag_id {
	MVOD_FLAG_CONFIG,
	MVOD_FLAG_PRINT_CONFIG,
	MVOD_FLAG_LIST_CAMERAS,
	MVOD_FLAG_HELP,
	MVOD_FLAG_HELP_ALL,
	MVOD_FLAG_MAN,
	MVOD_FLAG_VERSION,
	MVOD_FLAG_COUNT,
};

struct mvod_config_flag {
	const char *flag;   /* long option, without "--" */
	char short_flag;    /* or 0 */
	const char *arg;    /* its value's name, or NULL for none */
	bool every_command; /* every subcommand takes it (--help, --version); else mvod run only */
	const char *group;  /* the reference's heading it comes under ("General", ...) */
	const char *summary, *help; /* as a key's */
};

extern const struct mvod_config_flag mvod_config_flags[MVOD_FLAG_COUNT];

/* Defaults: those of mvod_run_opts_default and the comments above. */
void mvod_config_default(struct mvod_config *c);
/* Frees the owned strings; c is then as after mvod_config_default. NULL is a no-op. */
void mvod_config_fini(struct mvod_config *c);

/*
 * Sets key k from text (NULL for a bool's flag: flag_value). Strings are borrowed, for flags
 * whose argv outlives the config. On a bad value returns -EINVAL and puts what was expected
 * in err ("a number in [0.1, 1]"), for the caller to prefix with where the value came from.
 */
int mvod_config_set(struct mvod_config *c, int k, const char *text, char *err, size_t errlen);

/*
 * Parses INI text (len bytes, not necessarily NUL-terminated) over the defaults into out; name
 * is the file name for messages. An unknown section or key, a bad value or a malformed line is
 * -EINVAL with "NAME:LINE: ..." in err, naming the key, and out holds the defaults again. The
 * last of repeated keys wins; leading whitespace is insignificant (no continuation lines);
 * " ;" starts a comment; a line is at most MVOD_CONFIG_MAX_LINE characters.
 */
#define MVOD_CONFIG_MAX_LINE 198
int mvod_config_parse_buffer(const char *name, const char *text, size_t len,
			     struct mvod_config *out, char *err, size_t errlen);
/* The same for a file (at most 1 MiB): a missing file is an error too. */
int mvod_config_load(const char *path, struct mvod_config *out, char *err, size_t errlen);

/* Keys given in src replace those in dst (flags over the file); owned strings move to dst. */
void mvod_config_override(struct mvod_config *dst, struct mvod_config *src);
/* Fills what follows from other keys: the trajectory format from a *.kitti name. */
void mvod_config_finish(struct mvod_config *c);
/* Sets the log level from [log] level and quiet. */
void mvod_config_apply_log(const struct mvod_config *c);

/* Key k's value in c as --print-config writes it ("" for no string), into buf. */
void mvod_config_value_text(const struct mvod_config *c, int k, char *buf, size_t len);

/*
 * Writes c as an INI file that parses back to the same settings; a derived key not given is
 * written as a comment ("# format = tum"). A value INI cannot carry
 * (a newline, " ;", surrounding blanks, a line too long) is -EINVAL naming the key in err.
 */
int mvod_config_print(const struct mvod_config *c, FILE *out, char *err, size_t errlen);

/*
 * Whether the VO's options fit the mode and front end, each clash -EINVAL naming the options in
 * err (an option would otherwise be silently ignored): --frontend klt with a descriptor
 * option (mvod_vo_descriptor_option), --tracks where the descriptor front end runs, --mode
 * map with a detector other than ORB (its map keeps ORB descriptors). --features with klt is
 * no clash: a file may set ORB's count for when it runs; the run warns (pipeline/inputs.c).
 */
int mvod_config_check_frontend(const struct mvod_vo_params *p, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
