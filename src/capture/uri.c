#include "capture/uri.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/errbuf.h"

/* Longest key and value a source takes; device ids of libcamera are the longest values. */
#define KEY_MAX 32
#define VALUE_MAX 256

/* Splits "key=value" (len bytes of pair) into key and value. */
static int split_pair(const char *pair, size_t len, char *key, char *value, char *err,
		      size_t errlen)
{
	const char *eq = memchr(pair, '=', len);
	if (!eq || eq == pair)
		return mvod_errf(err, errlen, -EINVAL, "\"%.*s\" in the source URI is not key=value",
				 (int)len, pair);
	size_t klen = (size_t)(eq - pair), vlen = len - klen - 1;
	if (klen >= KEY_MAX || vlen >= VALUE_MAX)
		return mvod_errf(err, errlen, -EINVAL, "\"%.*s\" in the source URI is too long",
				 (int)len, pair);
	memcpy(key, pair, klen);
	key[klen] = '\0';
	memcpy(value, eq + 1, vlen);
	value[vlen] = '\0';
	return 0;
}

int mvod_uri_parse(const char *location, char *path, size_t pathlen, mvod_uri_param_fn param,
		   void *ctx, char *err, size_t errlen)
{
	const char *q = strchr(location, '?');
	size_t plen = q ? (size_t)(q - location) : strlen(location);
	if (plen >= pathlen)
		return mvod_errf(err, errlen, -ENAMETOOLONG, "source path too long: %.*s",
				 (int)plen, location);
	memcpy(path, location, plen);
	path[plen] = '\0';
	while (q && *q) {
		const char *pair = q + 1;
		q = strchr(pair, '&');
		size_t len = q ? (size_t)(q - pair) : strlen(pair);
		if (len == 0)
			continue;
		char key[KEY_MAX], value[VALUE_MAX];
		int ret = split_pair(pair, len, key, value, err, errlen);
		if (ret == 0)
			ret = param(ctx, key, value, err, errlen);
		if (ret < 0)
			return ret;
	}
	return 0;
}

int mvod_uri_int(const char *key, const char *value, long lo, long hi, long *out, char *err,
		 size_t errlen)
{
	char *end;
	errno = 0;
	long v = strtol(value, &end, 10);
	if (errno || end == value || *end || v < lo || v > hi)
		return mvod_errf(err, errlen, -EINVAL, "%s=%s: expected an integer in [%ld, %ld]",
				 key, value, lo, hi);
	*out = v;
	return 0;
}

int mvod_uri_positive(const char *key, const char *value, double hi, double *out, char *err,
		      size_t errlen)
{
	char *end;
	errno = 0;
	double v = strtod(value, &end);
	if (errno || end == value || *end || !isfinite(v) || v <= 0 || v > hi)
		return mvod_errf(err, errlen, -EINVAL, "%s=%s: expected a number in (0, %g]", key,
				 value, hi);
	*out = v;
	return 0;
}

int mvod_uri_unknown(const char *key, const char *known, char *err, size_t errlen)
{
	return mvod_errf(err, errlen, -EINVAL, "unknown source parameter \"%s\" (known: %s)", key,
			 known);
}
