#include "capture/images.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "capture/image_header.h"
#include "capture/path.h"
#include "mvod/log.h"
#include "util/input.h"
#include "util/lines.h"
#include "util/output.h"

/* Without a times.txt, frames are taken 10 Hz apart (KITTI's rate). */
#define DEFAULT_PERIOD_US 100000

/*
 * Bounds on a frame file, checked by the input path before a byte is read, so that one huge file
 * neither takes gigabytes of memory nor stays in the reused buffer. The first image may be
 * up to 256 MiB: an uncompressed 16-bit colour 8K frame (7680 x 4320 x 6 bytes) is 199 MB.
 * Later ones may be as large as the first image's size stored uncompressed at 16 bits and
 * 3 channels (the largest any format mvod reads makes of it) plus 1 MiB of headers and
 * metadata (EXIF thumbnails).
 */
#define FIRST_MAX_BYTES ((size_t)256 << 20)
#define HEADER_SLACK_BYTES ((size_t)1 << 20)

static bool is_image_name(const char *name)
{
	static const char *const exts[] = {"png", "jpg", "jpeg", "pgm", "ppm",
					   "bmp", "tif", "tiff"};
	const char *dot = strrchr(name, '.');
	/* Hidden files are editor and OS droppings (._0001.png from macOS), not frames. */
	if (name[0] == '.' || !dot)
		return false;
	for (size_t i = 0; i < sizeof(exts) / sizeof(exts[0]); i++)
		if (strcasecmp(dot + 1, exts[i]) == 0)
			return true;
	return false;
}

/* How many images d holds and the bytes their "dir/name" strings need. */
static void count_images(DIR *d, size_t dirlen, size_t *n, size_t *bytes)
{
	*n = 0;
	*bytes = 0;
	for (struct dirent *e = readdir(d); e; e = readdir(d)) {
		if (!is_image_name(e->d_name))
			continue;
		(*n)++;
		*bytes += dirlen + 1 + strlen(e->d_name) + 1;
	}
}

/* Fills up to n paths from the pool after paths[n]; returns how many fitted. */
static size_t fill_images(DIR *d, const char *dir, char **paths, size_t n, size_t bytes)
{
	char *pool = (char *)(paths + n);
	size_t k = 0;
	for (struct dirent *e = readdir(d); e && k < n; e = readdir(d)) {
		if (!is_image_name(e->d_name))
			continue;
		int len = snprintf(pool, bytes, "%s/%s", dir, e->d_name);
		/* The directory may have grown between the two passes; what fits is the list. */
		if (len < 0 || (size_t)len >= bytes)
			break;
		paths[k++] = pool;
		pool += len + 1;
		bytes -= (size_t)len + 1;
	}
	return k;
}

/*
 * The name's stem (up to the extension) as a number when it is one: digits with at most one
 * '.', e.g. "1.15" from "DIR/1.15.png" (timestamps as names). Signs and exponents are not
 * taken: no camera tool names frames so, and "1e3" may as well be a word.
 */
static bool stem_number(const char *path, double *v)
{
	const char *name = strrchr(path, '/');
	name = name ? name + 1 : path;
	const char *ext = strrchr(name, '.');
	size_t digits = strspn(name, "0123456789");
	const char *end = name + digits;
	if (*end == '.' && end != ext)
		end += 1 + strspn(end + 1, "0123456789");
	if (digits == 0 || end != ext)
		return false;
	*v = strtod(name, NULL);
	return true;
}

/* strverscmp, so that 2.png sorts before 10.png. */
static int compare_paths(const void *a, const void *b)
{
	return strverscmp(*(char *const *)a, *(char *const *)b);
}

/* By the number the names are (1.3 before 1.15 before 2), the version order between equals. */
static int compare_numbers(const void *a, const void *b)
{
	double x = 0, y = 0;
	stem_number(*(char *const *)a, &x);
	stem_number(*(char *const *)b, &y);
	return x < y ? -1 : x > y ? 1 : compare_paths(a, b);
}

/*
 * Numeric order when every name is a number, else version order: strverscmp puts 1.15 after
 * 1.3 (it compares 15 with 3), which is wrong for names that are timestamps in seconds.
 */
static void sort_images(char **paths, size_t n)
{
	bool numeric = true;
	double v;
	for (size_t i = 0; i < n && numeric; i++)
		numeric = stem_number(paths[i], &v);
	qsort(paths, n, sizeof(*paths), numeric ? compare_numbers : compare_paths);
}

static int list_images(struct mvod_images *im, const char *dir, char *err, size_t errlen)
{
	DIR *d = opendir(dir);
	if (!d)
		return mvod_errf(err, errlen, -errno, "cannot open image directory %s: %s",
					 dir, strerror(errno));
	int ret = 0;
	size_t n, bytes;
	count_images(d, strlen(dir), &n, &bytes);
	if (n > 0) {
		im->paths = malloc(n * sizeof(*im->paths) + bytes);
		if (!im->paths) {
			ret = mvod_errf(err, errlen, -ENOMEM, "out of memory listing %s",
						dir);
			goto out;
		}
		rewinddir(d);
		im->n = fill_images(d, dir, im->paths, n, bytes);
		sort_images(im->paths, im->n);
	}
	if (im->n == 0)
		ret = mvod_errf(err, errlen, -ENOENT,
					"no images in %s (looked for .png .jpg .jpeg .pgm .ppm "
					".bmp .tif .tiff)", dir);
out:
	closedir(d);
	return ret;
}

/* Seconds from the first token of line, as microseconds; -EINVAL when it is none. */
static int parse_seconds(const char *line, int64_t *us)
{
	char *end;
	double s = strtod(line, &end);
	/* 9e12 s is where int64 microseconds run out; the test also rejects nan. */
	if (end == line || !(fabs(s) < 9e12) || (*end && !isspace((unsigned char)*end)))
		return -EINVAL;
	*us = llround(s * 1e6);
	return 0;
}

/* times.txt as it is read: one time per image, into t[0..n), k of them so far. */
struct times {
	const char *path;
	int64_t *t;
	size_t n, k;
};

/* One line's time: 1 once the n-th is in (the rest of the file is not read). */
static int time_line(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct times *x = ctx;
	int64_t *t = x->t;
	if (parse_seconds(line, &t[x->k]) < 0)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: \"%.40s\" is not a time in "
				 "seconds", x->path, lineno, line);
	if (x->k > 0 && t[x->k] <= t[x->k - 1])
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: %.6f s is not after the line "
				 "before (%.6f s): times must increase, one line per image in name "
				 "order", x->path, lineno, t[x->k] / 1e6, t[x->k - 1] / 1e6);
	return ++x->k == x->n;
}

/* The n times of path, or -ENOENT when the file does not exist. */
static int load_times(struct mvod_images *im, const char *path, char *err, size_t errlen)
{
	if (access(path, F_OK) != 0 && errno == ENOENT)
		return -ENOENT;
	im->times_us = malloc(im->n * sizeof(*im->times_us));
	if (!im->times_us)
		return mvod_errf(err, errlen, -ENOMEM, "out of memory reading %s", path);
	struct times x = {path, im->times_us, im->n, 0};
	int ret = mvod_lines_each(path, "times.txt", time_line, &x, err, errlen);
	if (!ret && x.k < x.n)
		ret = mvod_errf(err, errlen, -EINVAL, "%s has %zu timestamps for %zu images; it "
				"needs one line per image", path, x.k, x.n);
	return ret;
}

/* Reads len bytes; -EIO when the file is shorter. */
static int read_all(struct mvod_input *in, uint8_t *buf, size_t len)
{
	for (size_t got = 0; got < len;) {
		ssize_t r = mvod_input_read(in, buf + got, len - got, NULL, 0);
		if (r < 0)
			return (int)r;
		if (r == 0)
			return -EIO;
		got += (size_t)r;
	}
	return 0;
}

/*
 * The whole of path into im->buf through the input path (noted at open; never blocking):
 * -EFBIG beyond im->limit, -ENODATA for no regular file.
 */
static int read_file(struct mvod_images *im, const char *path, size_t *len)
{
	struct mvod_input in;
	int ret = mvod_input_open(&in, path, "frame", MVOD_INPUT_NOTED, im->limit, NULL, 0);
	if (ret)
		return ret == -EINVAL || ret == -EISDIR ? -ENODATA : ret;
	size_t size = (size_t)in.size;
	if (size > im->cap) {
		uint8_t *grown = realloc(im->buf, size);
		ret = grown ? 0 : -ENOMEM;
		if (grown) {
			im->buf = grown;
			im->cap = size;
		}
	}
	if (!ret)
		ret = read_all(&in, im->buf, size);
	mvod_input_close(&in);
	*len = size;
	return ret;
}

/*
 * Image i decoded into the decoder's buffer once its header passed, *w x *h the size the
 * header states: -errno from reading (-EFBIG for too large a file), -EINVAL when it is no
 * image, -EMSGSIZE when the header states another size than the sequence's, -E2BIG a size
 * past MVOD_FRAME_MAX_PIXELS; none of these is decoded.
 */
static int load(struct mvod_images *im, size_t i, struct mvod_image *img, int *w, int *h)
{
	size_t len = 0;
	int ret = read_file(im, im->paths[i], &len);
	if (!ret)
		ret = mvod_image_header_size(im->buf, len, w, h);
	if (!ret && im->info.width && (*w != im->info.width || *h != im->info.height))
		ret = -EMSGSIZE;
	if (!ret && (int64_t)*w * *h > MVOD_FRAME_MAX_PIXELS)
		ret = -E2BIG;
	return ret ? ret : mvod_imgdec_decode(im->dec, im->buf, len, img);
}

/* The first image fixes the frame size and format of the whole sequence. */
static int load_first(struct mvod_images *im, char *err, size_t errlen)
{
	int ret = mvod_imgdec_create(&im->dec);
	if (ret < 0)
		return mvod_errf(err, errlen, ret, "cannot create an image decoder: %s",
					 strerror(-ret));
	struct mvod_image img;
	int w = 0, h = 0;
	im->limit = FIRST_MAX_BYTES;
	ret = load(im, 0, &img, &w, &h);
	if (ret == -E2BIG)
		return mvod_errf(err, errlen, ret, "%s is %dx%d pixels, its header says: more than "
				 "the %lld (8192x8192) of any frame mvod takes", im->paths[0], w, h,
				 (long long)MVOD_FRAME_MAX_PIXELS);
	if (ret == -EFBIG)
		return mvod_errf(err, errlen, ret, "%s is larger than %zu MiB, more than any camera "
					 "frame (an uncompressed 16-bit colour 8K frame is 190 MiB): not "
					 "a frame?", im->paths[0], FIRST_MAX_BYTES >> 20);
	if (ret == -ENODATA)
		return mvod_errf(err, errlen, -EINVAL, "%s is not a regular file (a FIFO, device "
					 "or folder named like an image)", im->paths[0]);
	if (ret == -EINVAL)
		return mvod_errf(err, errlen, ret, "cannot decode image %s (corrupt, or "
					 "not an image)", im->paths[0]);
	if (ret < 0)
		return mvod_errf(err, errlen, ret, "cannot read %s: %s", im->paths[0],
					 strerror(-ret));
	im->info.width = img.w;
	im->info.height = img.h;
	im->limit = (size_t)img.w * (size_t)img.h * 6 + HEADER_SLACK_BYTES;
	return 0;
}

/* The rate times.txt implies, 0 when it cannot tell. */
static double times_fps(const int64_t *t, size_t n)
{
	if (n < 2 || t[n - 1] <= t[0])
		return 0.0;
	return (double)(n - 1) * 1e6 / (double)(t[n - 1] - t[0]);
}

/*
 * Every frame is an input: no output of this process may be one (util/output.h). Noted here,
 * at open, so that reading one allocates nothing (MVOD_INPUT_NOTED); times.txt and a dataset's
 * index are noted by the line reader that reads them.
 */
static int note_frames(const struct mvod_images *im, char *err, size_t errlen)
{
	int ret = 0;
	size_t i = 0;
	for (; i < im->n && !ret; i++)
		ret = mvod_input_note(im->paths[i]);
	return ret ? mvod_errf(err, errlen, ret, "%s: %s", im->paths[i - 1], strerror(-ret)) : 0;
}

/* What every way of opening ends with: inputs noted, the first image decoded, info filled in. */
static int start(struct mvod_images *im, char *err, size_t errlen)
{
	int ret = note_frames(im, err, errlen);
	if (ret >= 0)
		ret = load_first(im, err, errlen);
	if (ret < 0)
		return ret;
	im->info.frames = (int64_t)im->n;
	im->info.focus = NAN;
	im->info.fps = im->times_us ? times_fps(im->times_us, im->n) : 1e6 / DEFAULT_PERIOD_US;
	return 0;
}

int mvod_images_open(struct mvod_images *im, const char *dir, const char *times_path, char *err,
		     size_t errlen)
{
	int ret = list_images(im, dir, err, errlen);
	if (ret < 0)
		goto fail;
	ret = load_times(im, times_path, err, errlen);
	if (ret < 0 && ret != -ENOENT)
		goto fail;
	ret = start(im, err, errlen);
	if (ret < 0)
		goto fail;
	im->info.times_assumed = !im->times_us;
	return 0;
fail:
	mvod_images_close(im);
	return ret;
}

int mvod_images_open_list(struct mvod_images *im, char **paths, size_t n, int64_t *times_us,
			  char *err, size_t errlen)
{
	im->paths = paths;
	im->n = n;
	im->times_us = times_us;
	int ret = start(im, err, errlen);
	if (ret < 0)
		mvod_images_close(im);
	return ret;
}

int mvod_images_read(void *priv, struct mvod_frame *frame, const struct mvod_image *into)
{
	(void)into; /* images decode into their own buffer */
	struct mvod_images *im = priv;
	if (im->next >= im->n)
		return -ENODATA;
	size_t i = im->next++;
	/* Index and time first, so that a caller reporting a bad frame can name it. */
	frame->index = (int64_t)i;
	frame->utime = im->times_us ? im->times_us[i] : (int64_t)i * DEFAULT_PERIOD_US;
	/* One unreadable file is one bad frame (-EINVAL, which callers skip), not a broken source. */
	int w, h;
	int ret = load(im, i, &frame->img, &w, &h);
	if (ret == 0)
		return 0;
	frame->bad = ret == -EFBIG      ? MVOD_BAD_TOO_LARGE
		     : ret == -EMSGSIZE ? MVOD_BAD_SIZE
		     : ret == -EINVAL   ? MVOD_BAD_CORRUPT
					: MVOD_BAD_UNREADABLE;
	return -EINVAL;
}

void mvod_images_info(void *priv, struct mvod_source_info *info)
{
	const struct mvod_images *im = priv;
	*info = im->info;
}

void mvod_images_close(void *priv)
{
	struct mvod_images *im = priv;
	mvod_imgdec_destroy(im->dec);
	free(im->buf);
	free(im->times_us);
	free(im->paths);
	*im = (struct mvod_images){0};
}

static int images_open(void *priv, const char *dir, char *err, size_t errlen)
{
	char times_path[PATH_MAX];
	int ret = mvod_capture_path(times_path, sizeof(times_path), dir, "times.txt", err, errlen);
	if (ret < 0)
		return ret;
	return mvod_images_open(priv, dir, times_path, err, errlen);
}

const struct mvod_source_ops mvod_source_images_ops = {
	.scheme = "images",
	.summary = "images:DIR  sorted image files (png, jpg, pgm, ppm, bmp, tiff), optional "
		   "DIR/times.txt in seconds",
	.priv_size = sizeof(struct mvod_images),
	.open = images_open,
	.read = mvod_images_read,
	.info = mvod_images_info,
	.camera = NULL,
	.close = mvod_images_close,
};
