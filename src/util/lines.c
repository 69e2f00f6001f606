#include "util/lines.h"

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "util/errbuf.h"
#include "util/input.h"

struct mvod_lines {
	struct mvod_input in;
	size_t lineno;     /* of the line last handed out */
	size_t start, end; /* the bytes read and not yet handed out: buf[start, end) */
	bool eof;
	char buf[MVOD_LINE_MAX + 1]; /* + 1: the NUL after a last line without its end */
};

int mvod_lines_open(const char *path, const char *what, struct mvod_lines **out, char *err,
		    size_t errlen)
{
	struct mvod_lines *l = malloc(sizeof(*l));
	if (!l)
		return mvod_errf(err, errlen, -ENOMEM, "cannot read %s: out of memory", path);
	*l = (struct mvod_lines){.lineno = 0};
	int ret = mvod_input_open(&l->in, path, what, 0, MVOD_LINES_MAX_BYTES, err, errlen);
	if (ret) {
		free(l);
		return ret;
	}
	*out = l;
	return 0;
}

void mvod_lines_close(struct mvod_lines *l)
{
	if (!l)
		return;
	mvod_input_close(&l->in);
	free(l);
}

/*
 * Tab, LF, VT, FF and CR are the control characters text holds; any other (NUL first of all)
 * says the file is binary, or not the text it was named as.
 */
static int check_text(const struct mvod_lines *l, const char *s, size_t n, char *err,
		      size_t errlen)
{
	for (size_t i = 0; i < n; i++) {
		unsigned char c = (unsigned char)s[i];
		if (c < 0x20 && (c < '\t' || c > '\r'))
			return mvod_errf(err, errlen, -EILSEQ, "%s line %zu: byte 0x%02x "
					 "at column %zu is no text: not a %s", l->in.path,
					 l->lineno, c, i + 1, l->in.what);
	}
	return 0;
}

/* The line at buf[start] up to nl (or to end, the last line): cut, checked, handed out. */
static int take(struct mvod_lines *l, char *nl, char **line, char *err, size_t errlen)
{
	char *s = l->buf + l->start;
	size_t n = nl ? (size_t)(nl - s) : l->end - l->start;
	l->start += n + (nl != NULL);
	s[n] = '\0';
	if (n > 0 && s[n - 1] == '\r')
		s[--n] = '\0';
	if (++l->lineno == 1 && strncmp(s, "\xEF\xBB\xBF", 3) == 0) {
		s += 3;
		n -= 3;
	}
	int ret = check_text(l, s, n, err, errlen);
	*line = s;
	return ret ? ret : 1;
}

/* More bytes after the unread ones, moved to the front: 0, or -errno (a line too long). */
static int fill(struct mvod_lines *l, char *err, size_t errlen)
{
	memmove(l->buf, l->buf + l->start, l->end - l->start);
	l->end -= l->start;
	l->start = 0;
	if (l->end == MVOD_LINE_MAX)
		return mvod_errf(err, errlen, -E2BIG, "%s line %zu is longer than %d bytes: no "
				 "line of a %s is (a binary or corrupt file?)", l->in.path,
				 l->lineno + 1, MVOD_LINE_MAX - 1, l->in.what);
	ssize_t r = mvod_input_read(&l->in, l->buf + l->end, MVOD_LINE_MAX - l->end, err, errlen);
	if (r < 0)
		return (int)r;
	l->eof = r == 0;
	l->end += (size_t)r;
	return 0;
}

int mvod_lines_next(struct mvod_lines *l, char **line, size_t *lineno, char *err,
		    size_t errlen)
{
	for (;;) {
		char *nl = memchr(l->buf + l->start, '\n', l->end - l->start);
		int ret = 0;
		if (nl || (l->eof && l->end > l->start))
			ret = take(l, nl, line, err, errlen);
		else if (!l->eof)
			ret = fill(l, err, errlen);
		*lineno = l->lineno;
		if (ret || (l->eof && l->start == l->end))
			return ret;
	}
}

int mvod_lines_each(const char *path, const char *what, mvod_line_fn fn, void *ctx, char *err,
		    size_t errlen)
{
	struct mvod_lines *l = NULL;
	int ret = mvod_lines_open(path, what, &l, err, errlen);
	char *line;
	size_t lineno;
	while (!ret && (ret = mvod_lines_next(l, &line, &lineno, err, errlen)) > 0) {
		const char *s = line + strspn(line, " \t");
		ret = *s && *s != '#' ? fn(ctx, line, lineno, err, errlen) : 0;
	}
	mvod_lines_close(l);
	return ret < 0 ? ret : 0;
}
