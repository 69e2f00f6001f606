#include "util/input.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/errbuf.h"
#include "util/output.h"

/* What st is, for a refusal: "a FIFO", "a character device" ... */
static const char *kind_name(const struct stat *st)
{
	return S_ISFIFO(st->st_mode)   ? "a FIFO"
	       : S_ISCHR(st->st_mode)  ? "a character device"
	       : S_ISBLK(st->st_mode)  ? "a block device"
	       : S_ISSOCK(st->st_mode) ? "a socket"
				       : "no regular file";
}

static int too_large(const struct mvod_input *in, char *err, size_t errlen)
{
	return mvod_errf(err, errlen, -EFBIG, "%s is larger than %zu bytes: not a %s", in->path,
			 in->max, in->what);
}

/* Whether the file open as st may be read as in's what: 0 or -errno with the reason. */
static int check_type(struct mvod_input *in, const struct stat *st, int flags, char *err,
		      size_t errlen)
{
	if (S_ISDIR(st->st_mode))
		return mvod_errf(err, errlen, -EISDIR, "%s is a directory: name the %s, a file",
				 in->path, in->what);
	if (S_ISREG(st->st_mode) && (size_t)st->st_size > in->max)
		return too_large(in, err, errlen);
	if (S_ISREG(st->st_mode) || (S_ISFIFO(st->st_mode) && (flags & MVOD_INPUT_STREAM)))
		return 0;
	return mvod_errf(err, errlen, -EINVAL, "%s is %s: the %s must be a regular file",
			 in->path, kind_name(st), in->what);
}

/*
 * Opened without blocking, so that a FIFO nobody writes into cannot hang mvod before its
 * watchdog runs: its first read says 0 (no writer) and it is refused at once; EAGAIN means a
 * writer is there, and from then on reads block as they do on a pipe.
 */
int mvod_input_open(struct mvod_input *in, const char *path, const char *what, int flags,
		    size_t max, char *err, size_t errlen)
{
	*in = (struct mvod_input){.fd = -1, .first = true, .max = max, .path = path, .what = what};
	int ret = flags & MVOD_INPUT_NOTED ? 0 : mvod_input_note(path);
	in->fd = ret ? -1 : open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
	if (!ret && in->fd < 0)
		ret = -errno;
	struct stat st;
	if (!ret && fstat(in->fd, &st) != 0)
		ret = -errno;
	if (ret) {
		mvod_input_close(in);
		return mvod_errf(err, errlen, ret, "cannot read %s: %s", path, strerror(-ret));
	}
	ret = check_type(in, &st, flags, err, errlen);
	if (ret) {
		mvod_input_close(in);
		return ret;
	}
	in->fifo = S_ISFIFO(st.st_mode);
	in->size = in->fifo ? -1 : st.st_size;
	return 0;
}

ssize_t mvod_input_read(struct mvod_input *in, void *buf, size_t len, char *err, size_t errlen)
{
	for (;;) {
		ssize_t r = read(in->fd, buf, len);
		if (r == 0 && in->fifo && in->first)
			return mvod_errf(err, errlen, -ENXIO, "%s is a FIFO that no process writes "
					 "into: start the writer first, or name a file as the %s",
					 in->path, in->what);
		if (r < 0 && errno == EAGAIN && fcntl(in->fd, F_SETFL, 0) == 0)
			continue;
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0)
			return mvod_errf(err, errlen, -errno, "cannot read %s: %s", in->path,
					 strerror(errno));
		in->first = false;
		in->got += (size_t)r;
		/* A stream, or a file that grew while it was read. */
		if (in->got > in->max)
			return too_large(in, err, errlen);
		return r;
	}
}

void mvod_input_close(struct mvod_input *in)
{
	if (in->fd >= 0)
		close(in->fd);
	in->fd = -1;
}
