#include "util/read_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stdbool.h>
#include <sys/stat.h>

#include "util/errbuf.h"
#include "util/output.h"

/* The buffer doubles from a page up to max + 1 bytes, the first byte too many. */
static int grow(char **buf, size_t *cap, size_t max)
{
	size_t want = *cap ? 2 * *cap : 4096;
	size_t next = want > max + 1 ? max + 1 : want;
	char *b = realloc(*buf, next + 1);
	if (!b)
		return -ENOMEM;
	*buf = b;
	*cap = next;
	return 0;
}

/*
 * Opened without blocking, so that a FIFO nobody writes into cannot hang mvod before its
 * watchdog runs: its first read says 0 (no writer) and it is refused at once; EAGAIN means a
 * writer is there, and from then on reads block as they do on a pipe. The file is noted as an
 * input: no output of this process may be it. Returns the descriptor or -errno.
 */
static int open_input(const char *path, bool *fifo, char *err, size_t errlen)
{
	int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
	if (fd < 0)
		return mvod_errf(err, errlen, -errno, "cannot read %s: %s", path, strerror(errno));
	struct stat st;
	int ret = fstat(fd, &st) != 0 ? -errno : mvod_input_note(path);
	if (ret) {
		close(fd);
		return mvod_errf(err, errlen, ret, "cannot read %s: %s", path, strerror(-ret));
	}
	*fifo = S_ISFIFO(st.st_mode);
	return fd;
}

int mvod_read_file(const char *path, size_t max, const char *what, char **out, size_t *len, char *err,
		   size_t errlen)
{
	bool fifo = false;
	int fd = open_input(path, &fifo, err, errlen);
	if (fd < 0)
		return fd;
	char *buf = NULL;
	size_t n = 0, cap = 0;
	int ret = 0;
	for (;;) {
		if (n == cap && n > max) {
			ret = mvod_errf(err, errlen, -EFBIG, "%s is larger than %zu bytes: not a %s", path, max,
					what);
			break;
		}
		if (n == cap && (ret = grow(&buf, &cap, max)) != 0) {
			mvod_errf(err, errlen, ret, "cannot read %s: out of memory", path);
			break;
		}
		ssize_t r = read(fd, buf + n, cap - n);
		if (r == 0 && fifo && n == 0)
			ret = mvod_errf(err, errlen, -ENXIO, "%s is a FIFO that no process writes into: "
					"start the writer first, or name a file as the %s", path, what);
		if (r == 0)
			break;
		if (r < 0 && errno == EAGAIN && fcntl(fd, F_SETFL, 0) == 0)
			continue;
		if (r < 0 && errno != EINTR) {
			ret = mvod_errf(err, errlen, -errno, "cannot read %s: %s", path, strerror(errno));
			break;
		}
		n += r > 0 ? (size_t)r : 0;
	}
	close(fd);
	if (ret) {
		free(buf);
		return ret;
	}
	buf[n] = '\0';
	*out = buf;
	if (len)
		*len = n;
	return 0;
}

int mvod_read_lines(const char *path, mvod_line_fn fn, void *ctx, char *err, size_t errlen)
{
	/* An input: no output of this process may be it (util/output.h). */
	int ret = mvod_input_note(path);
	if (ret < 0)
		return mvod_errf(err, errlen, ret, "%s: %s", path, strerror(-ret));
	FILE *f = fopen(path, "re");
	if (!f)
		return mvod_errf(err, errlen, -errno, "cannot read %s: %s", path, strerror(errno));
	char *line = NULL;
	size_t cap = 0, lineno = 0;
	while (!ret && getline(&line, &cap, f) >= 0) {
		lineno++;
		line[strcspn(line, "\r\n")] = '\0';
		const char *s = line + strspn(line, " \t");
		if (*s && *s != '#')
			ret = fn(ctx, line, lineno, err, errlen);
	}
	/* getline ends on errors too (a directory: EISDIR), which are no end of the file. */
	int read_errno = ferror(f) ? (errno ? errno : EIO) : 0;
	if (!ret && read_errno)
		ret = mvod_errf(err, errlen, -read_errno, "cannot read %s: %s", path,
				strerror(read_errno));
	free(line);
	fclose(f);
	return ret < 0 ? ret : 0;
}
