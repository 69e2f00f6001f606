/*
 * The "?key=value&key=value" tail of a source URI (v4l2:/dev/video0?width=640&fps=30). Each
 * backend names the keys it takes through a callback; anything else is an error that names it.
 */
#ifndef MVOD_CAPTURE_URI_H
#define MVOD_CAPTURE_URI_H

#include <stddef.h>

/* Takes one key=value; returns 0, or -EINVAL with the reason in err (unknown key, bad value). */
typedef int (*mvod_uri_param_fn)(void *ctx, const char *key, const char *value, char *err,
				 size_t errlen);

/*
 * Copies what precedes the first '?' of location into path and hands every pair after it to
 * param, in order. -ENAMETOOLONG or -EINVAL (a pair without '=', a key or value too long, or
 * what param returned) with the reason in err.
 */
int mvod_uri_parse(const char *location, char *path, size_t pathlen, mvod_uri_param_fn param,
		   void *ctx, char *err, size_t errlen);

/* A base-10 integer in [lo, hi] for key, or -EINVAL saying what was expected. */
int mvod_uri_int(const char *key, const char *value, long lo, long hi, long *out, char *err,
		 size_t errlen);
/* A positive finite number in (0, hi] for key, or -EINVAL saying what was expected. */
int mvod_uri_positive(const char *key, const char *value, double hi, double *out, char *err,
		      size_t errlen);
/* The reason for a key the backend does not take, listing those it does. */
int mvod_uri_unknown(const char *key, const char *known, char *err, size_t errlen);

#endif
