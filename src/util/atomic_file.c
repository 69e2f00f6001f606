#include "util/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/output.h"

/* Same directory as the target (rename is atomic only within one file system), hidden name. */
static int temp_name(const char *path, unsigned n, char *out, size_t len)
{
	const char *slash = strrchr(path, '/');
	int dir_len = slash ? (int)(slash - path + 1) : 0;
	int w = snprintf(out, len, "%.*s.%s.tmp-%ld-%u", dir_len, path, path + dir_len,
			 (long)getpid(), n);
	return w < 0 || (size_t)w >= len ? -ENAMETOOLONG : 0;
}

/* O_EXCL with a fresh name on collision; 0666 lets the umask decide the mode. */
static int open_temp(const char *path, char *tmp, size_t len)
{
	static atomic_uint counter;
	for (int attempt = 0; attempt < 100; attempt++) {
		int ret = temp_name(path, atomic_fetch_add(&counter, 1), tmp, len);
		if (ret)
			return ret;
		int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd >= 0 || errno != EEXIST)
			return fd >= 0 ? fd : -errno;
	}
	return -EEXIST;
}

static int write_all(int fd, const char *buf, size_t len)
{
	for (size_t off = 0; off < len;) {
		ssize_t w = write(fd, buf + off, len - off);
		if (w < 0 && errno == EINTR)
			continue;
		if (w < 0)
			return -errno;
		off += (size_t)w;
	}
	return 0;
}

/* Temp+rename over the regular file (or nothing) at target, keeping its permissions. */
static int replace(const char *target, const void *buf, size_t len)
{
	char tmp[PATH_MAX + 64];
	struct stat old;
	int fd = open_temp(target, tmp, sizeof(tmp));
	if (fd < 0)
		return fd;
	int ret = write_all(fd, buf, len);
	if (!ret && stat(target, &old) == 0 && fchmod(fd, old.st_mode & 07777) != 0)
		ret = -errno;
	if (!ret && fsync(fd) != 0)
		ret = -errno;
	if (close(fd) != 0 && !ret)
		ret = -errno;
	if (!ret && rename(tmp, target) != 0)
		ret = -errno;
	if (ret)
		unlink(tmp);
	return ret;
}

/*
 * Into a device or FIFO. The FIFO is opened without blocking, so one without a reader is
 * -ENXIO at once; then blocking, as a shell's "> fifo" writes, since a reader is there.
 */
static int write_into(const char *target, bool fifo, const void *buf, size_t len)
{
	int fd = open(target, O_WRONLY | O_CLOEXEC | O_NOCTTY | (fifo ? O_NONBLOCK : 0));
	if (fd < 0)
		return -errno;
	int ret = fifo && fcntl(fd, F_SETFL, 0) != 0 ? -errno : 0;
	if (!ret)
		ret = write_all(fd, buf, len);
	if (close(fd) != 0 && !ret)
		ret = -errno;
	return ret;
}

int mvod_write_replace(const char *path, const void *buf, size_t len)
{
	char target[PATH_MAX];
	enum mvod_output_kind kind;
	int ret = mvod_output_check("output", path, target, sizeof(target), &kind, NULL, 0);
	if (ret)
		return ret;
	if (kind == MVOD_OUTPUT_DEVICE || kind == MVOD_OUTPUT_FIFO)
		return write_into(target, kind == MVOD_OUTPUT_FIFO, buf, len);
	return replace(target, buf, len);
}
