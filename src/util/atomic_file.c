#include "util/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

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

int mvod_write_replace(const char *path, const void *buf, size_t len)
{
	char tmp[4096];
	int fd = open_temp(path, tmp, sizeof(tmp));
	if (fd < 0)
		return fd;
	int ret = write_all(fd, buf, len);
	if (!ret && fsync(fd) != 0)
		ret = -errno;
	if (close(fd) != 0 && !ret)
		ret = -errno;
	if (!ret && rename(tmp, path) != 0)
		ret = -errno;
	if (ret)
		unlink(tmp);
	return ret;
}
