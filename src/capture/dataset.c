#include "capture/dataset.h"

#include <assert.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capture/path.h"
#include "util/output.h"

static_assert(offsetof(struct mvod_dataset, images) == 0, "the images ops take the dataset priv");

/*
 * Decimal digits at s, at most max of them, into *v; how many were read, or -1 when more
 * follow or the value would pass INT64_MAX.
 */
static int parse_digits(const char *s, int max, const char **end, int64_t *v)
{
	int k = 0;
	*v = 0;
	for (; s[k] >= '0' && s[k] <= '9'; k++) {
		int d = s[k] - '0';
		if (k == max || *v > (INT64_MAX - d) / 10)
			return -1;
		*v = 10 * *v + d;
	}
	*end = s + k;
	return k;
}

int mvod_ds_parse_ns(const char *s, const char **end, int64_t *ns)
{
	s += strspn(s, " \t");
	return parse_digits(s, 19, end, ns) > 0 ? 0 : -EINVAL;
}

/* Digits after a decimal point at *s, if there is one, as nanoseconds: the first 9 kept. */
static int64_t fraction_ns(const char **s)
{
	int64_t frac = 0;
	int frac_digits = 0;
	if (**s != '.')
		return 0;
	const char *f = *s + 1;
	for (; *f >= '0' && *f <= '9'; f++) {
		if (frac_digits == 9)
			continue; /* below a nanosecond: dropped */
		frac = 10 * frac + (*f - '0');
		frac_digits++;
	}
	*s = f;
	for (int k = frac_digits; k < 9; k++)
		frac *= 10;
	return frac;
}

int mvod_ds_parse_seconds(const char *s, const char **end, int64_t *ns)
{
	s += strspn(s, " \t");
	int64_t sec;
	/* Int64 nanoseconds end in the year 2262, a second after INT64_MAX / 1e9 s. */
	if (parse_digits(s, 10, end, &sec) <= 0 || sec >= INT64_MAX / 1000000000)
		return -EINVAL;
	*ns = sec * 1000000000 + fraction_ns(end);
	return 0;
}

/* Days from 1970-01-01 to y-m-d in the proleptic Gregorian calendar (eras of 400 years). */
static int64_t days_from_civil(int64_t y, int64_t m, int64_t d)
{
	y -= m <= 2;
	const int64_t era = y / 400, yoe = y - era * 400;         /* y >= 0 here: 1970..2261 */
	const int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1; /* from March 1st */
	const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
	return era * 146097 + doe - 719468;
}

static bool leap(int64_t y)
{
	return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
}

int mvod_ds_parse_calendar(const char *s, const char **end, int64_t *ns)
{
	/* YYYY-MM-DD HH:MM:SS: each field's digits, then what must follow it. */
	static const struct {
		int digits;
		char after;
		int64_t lo, hi;
	} f[6] = {{4, '-', 1970, 2261}, {2, '-', 1, 12}, {2, ' ', 1, 31},
		  {2, ':', 0, 23},      {2, ':', 0, 59}, {2, 0, 0, 59}};
	static const int mdays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
	int64_t v[6];
	s += strspn(s, " \t");
	for (int i = 0; i < 6; i++) {
		if (parse_digits(s, f[i].digits, &s, &v[i]) != f[i].digits || v[i] < f[i].lo ||
		    v[i] > f[i].hi || (f[i].after && *s++ != f[i].after))
			return -EINVAL;
	}
	if (v[2] > mdays[v[1] - 1] + (v[1] == 2 && leap(v[0])))
		return -EINVAL;
	int64_t sec = days_from_civil(v[0], v[1], v[2]) * 86400 + v[3] * 3600 + v[4] * 60 + v[5];
	*ns = sec * 1000000000 + fraction_ns(&s);
	*end = s;
	return 0;
}

const char *mvod_ds_seconds(int64_t ns, char buf[24])
{
	snprintf(buf, 24, "%" PRId64 ".%09" PRId64, ns / 1000000000, ns % 1000000000);
	return buf;
}

int mvod_ds_out_of_order(const char *path, size_t lineno, int64_t ns, int64_t prev,
			 size_t prev_line, const char *what, char *err, size_t errlen)
{
	char a[24], b[24];
	return mvod_errf(err, errlen, -EINVAL, "%s line %zu: time %s s is not after %s s of line "
			 "%zu: the %s must be in time order", path, lineno, mvod_ds_seconds(ns, a),
			 mvod_ds_seconds(prev, b), prev_line, what);
}

int mvod_ds_parse_pose(const char *s, char sep, bool w_first, struct mvod_pose *p, char *why,
		       size_t whylen)
{
	double v[7];
	for (int k = 0; k < 7; k++) {
		const char *before = s;
		s += strspn(s, " \t");
		if (sep == ' ' ? s == before : *s++ != sep)
			return -EINVAL;
		char *end;
		v[k] = strtod(s, &end);
		if (end == s || !isfinite(v[k]))
			return -EINVAL;
		s = end;
	}
	s += strspn(s, " \t");
	if (*s && (sep == ' ' || *s != sep))
		return -EINVAL;
	const double q[4] = {w_first ? v[3] : v[6], v[w_first ? 4 : 3], v[w_first ? 5 : 4],
			     v[w_first ? 6 : 5]};
	return mvod_pose_from_quat(v, q, p, why, whylen);
}

/* Appends "dir/name\0" to the text of f. */
static int push_path(struct mvod_ds_frames *f, const char *dir, const char *name)
{
	size_t need = strlen(dir) + 1 + strlen(name) + 1;
	if (f->len + need > f->cap) {
		size_t cap = f->cap ? 2 * f->cap : 65536;
		while (cap < f->len + need)
			cap *= 2;
		char *text = realloc(f->text, cap);
		if (!text)
			return -ENOMEM;
		f->text = text;
		f->cap = cap;
	}
	f->len += (size_t)sprintf(f->text + f->len, "%s/%s", dir, name) + 1;
	return 0;
}

static int push_time(struct mvod_ds_frames *f, int64_t ns)
{
	if (f->n == f->ncap) {
		size_t cap = f->ncap ? 2 * f->ncap : 1024;
		int64_t *grown = realloc(f->ns, cap * sizeof(*grown));
		if (!grown)
			return -ENOMEM;
		f->ns = grown;
		f->ncap = cap;
	}
	f->ns[f->n++] = ns;
	return 0;
}

/* ns to the microseconds of struct mvod_frame, to the nearest (times are not negative). */
static int64_t ns_to_us(int64_t ns)
{
	return ns / 1000 + (ns % 1000 >= 500); /* not (ns + 500) / 1000: no overflow at the end */
}

int mvod_ds_frames_add(struct mvod_ds_frames *f, const char *index, size_t lineno,
		       const char *dir, const char *name, int64_t ns, char *err, size_t errlen)
{
	/*
	 * Frames go on in microseconds (struct mvod_frame's utime): two in one microsecond were
	 * two frames at one time downstream (found by fuzz/euroc_index).
	 */
	if (f->n > 0 && ns_to_us(ns) <= ns_to_us(f->ns[f->n - 1]))
		return mvod_ds_out_of_order(index, lineno, ns, f->ns[f->n - 1], f->last_line,
					    "frames (to the microsecond)", err, errlen);
	int ret = push_path(f, dir, name);
	if (ret == 0)
		ret = push_time(f, ns);
	if (ret < 0)
		return mvod_errf(err, errlen, ret, "out of memory reading %s", index);
	const char *path = f->text + f->len - (strlen(dir) + strlen(name) + 2);
	if (access(path, F_OK) != 0)
		return mvod_errf(err, errlen, -ENOENT, "%s line %zu names %s, which does not exist: "
				 "is the sequence complete?", index, lineno, path);
	if (f->n == 1)
		f->first_line = lineno;
	f->last_line = lineno;
	return 0;
}

/* The one allocation of pointers and strings that struct mvod_images holds. */
static char **pack_paths(const struct mvod_ds_frames *f)
{
	char **paths = malloc(f->n * sizeof(*paths) + f->len);
	if (!paths)
		return NULL;
	char *pool = memcpy(paths + f->n, f->text, f->len);
	for (size_t i = 0; i < f->n; i++) {
		paths[i] = pool;
		pool += strlen(pool) + 1;
	}
	return paths;
}

int mvod_ds_open_frames(struct mvod_dataset *ds, struct mvod_ds_frames *f, char *err,
			size_t errlen)
{
	int ret = 0;
	char **paths = NULL;
	int64_t *us = NULL;
	if (f->n == 0) {
		ret = mvod_errf(err, errlen, -ENOENT, "%s names no frames", ds->index);
		goto out;
	}
	paths = pack_paths(f);
	us = malloc(f->n * sizeof(*us));
	if (!paths || !us) {
		ret = mvod_errf(err, errlen, -ENOMEM, "out of memory reading %s", ds->index);
		goto out;
	}
	for (size_t i = 0; i < f->n; i++)
		us[i] = ns_to_us(f->ns[i]);
	ret = mvod_images_open_list(&ds->images, paths, f->n, us, err, errlen);
	paths = NULL; /* the images' now, or freed */
	us = NULL;
	if (ret == 0) {
		ds->frame_ns = f->ns;
		f->ns = NULL;
		ds->index_first = f->first_line;
		ds->index_last = f->last_line;
	}
out:
	free(paths);
	free(us);
	mvod_ds_frames_free(f);
	return ret;
}

void mvod_ds_frames_free(struct mvod_ds_frames *f)
{
	free(f->text);
	free(f->ns);
	*f = (struct mvod_ds_frames){0};
}

int mvod_ds_camera(void *priv, struct mvod_camera *cam)
{
	const struct mvod_dataset *ds = priv;
	if (!ds->has_cam)
		return -ENOENT;
	*cam = ds->cam;
	return 0;
}

void mvod_ds_close(void *priv)
{
	struct mvod_dataset *ds = priv;
	mvod_images_close(&ds->images);
	free(ds->frame_ns);
	ds->frame_ns = NULL;
}

int mvod_ds_optional(char *buf, size_t len, const char *dir, const char *name, char *err,
		     size_t errlen)
{
	int ret = mvod_capture_path(buf, len, dir, name, err, errlen);
	if (ret == 0 && access(buf, F_OK) != 0)
		buf[0] = '\0';
	return ret;
}
