#include "util/output.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/errbuf.h"

/* --- inputs, by device and inode --- */

struct input {
	dev_t dev;
	ino_t ino;
	char *path; /* owned: to tell the input from a later file that reuses its inode */
};

/*
 * Grown by doubling while sources and files open (a KITTI folder notes ~5 000 frames), never
 * per frame. The lock is for a live source reopened by its capture thread.
 */
static struct {
	pthread_mutex_t lock;
	struct input *in;
	size_t n, cap;
} inputs = {.lock = PTHREAD_MUTEX_INITIALIZER};

int mvod_input_note(const char *path)
{
	struct stat st;
	if (stat(path, &st) != 0)
		return errno == ENOENT || errno == ENOTDIR ? 0 : -errno;
	char *copy = strdup(path);
	int ret = copy ? 0 : -ENOMEM;
	pthread_mutex_lock(&inputs.lock);
	if (!ret && inputs.n == inputs.cap) {
		size_t cap = inputs.cap ? 2 * inputs.cap : 64;
		struct input *in = realloc(inputs.in, cap * sizeof(*in));
		if (in) {
			inputs.in = in;
			inputs.cap = cap;
		}
		ret = in ? 0 : -ENOMEM;
	}
	if (!ret)
		inputs.in[inputs.n++] = (struct input){st.st_dev, st.st_ino, copy};
	pthread_mutex_unlock(&inputs.lock);
	if (ret)
		free(copy);
	return ret;
}

void mvod_inputs_forget(void)
{
	pthread_mutex_lock(&inputs.lock);
	for (size_t i = 0; i < inputs.n; i++)
		free(inputs.in[i].path);
	free(inputs.in);
	inputs.in = NULL;
	inputs.n = inputs.cap = 0;
	pthread_mutex_unlock(&inputs.lock);
}

void mvod_input_release(const char *path)
{
	struct stat st;
	if (stat(path, &st) != 0)
		return;
	pthread_mutex_lock(&inputs.lock);
	for (size_t i = 0; i < inputs.n;) {
		if (inputs.in[i].dev == st.st_dev && inputs.in[i].ino == st.st_ino) {
			free(inputs.in[i].path);
			inputs.in[i] = inputs.in[--inputs.n];
		} else {
			i++;
		}
	}
	pthread_mutex_unlock(&inputs.lock);
}

/*
 * The same device and inode as an input whose name still leads to it: a file deleted after it
 * was read may give its inode number to a new file, which is no input.
 */
static bool is_input(const struct stat *st)
{
	bool found = false;
	struct stat now;
	pthread_mutex_lock(&inputs.lock);
	for (size_t i = 0; i < inputs.n && !found; i++)
		found = inputs.in[i].dev == st->st_dev && inputs.in[i].ino == st->st_ino &&
			stat(inputs.in[i].path, &now) == 0 && now.st_dev == st->st_dev &&
			now.st_ino == st->st_ino;
	pthread_mutex_unlock(&inputs.lock);
	return found;
}

/* --- the policy --- */

/*
 * Follows path through symlinks into out, link by link, so a dangling link resolves to the
 * name it points at (created there) and a relative target is taken from the link's folder.
 */
static int resolve(const char *path, char *out, size_t len)
{
	if ((size_t)snprintf(out, len, "%s", path) >= len)
		return -ENAMETOOLONG;
	for (int hops = 0; hops < 40; hops++) {
		struct stat st;
		if (lstat(out, &st) != 0 || !S_ISLNK(st.st_mode))
			return 0; /* what is not there is created by name; open says why it cannot */
		char link[PATH_MAX], next[PATH_MAX];
		ssize_t n = readlink(out, link, sizeof(link) - 1);
		if (n < 0)
			return -errno;
		link[n] = '\0';
		const char *slash = strrchr(out, '/');
		int dir_len = link[0] != '/' && slash ? (int)(slash - out + 1) : 0;
		if ((size_t)snprintf(next, sizeof(next), "%.*s%s", dir_len, out, link) >= sizeof(next) ||
		    (size_t)snprintf(out, len, "%s", next) >= len)
			return -ENAMETOOLONG;
	}
	return -ELOOP;
}

static int kind_of(const char *what, const char *path, const struct stat *st,
		   enum mvod_output_kind *kind, char *err, size_t errlen)
{
	if (S_ISREG(st->st_mode))
		*kind = MVOD_OUTPUT_REGULAR;
	else if (S_ISCHR(st->st_mode))
		*kind = MVOD_OUTPUT_DEVICE;
	else if (S_ISFIFO(st->st_mode))
		*kind = MVOD_OUTPUT_FIFO;
	else if (S_ISDIR(st->st_mode))
		return mvod_errf(err, errlen, -EISDIR, "%s %s is a directory: name a file", what, path);
	else
		return mvod_errf(err, errlen, -EPERM, "%s %s is a %s: mvod writes files, character "
				 "devices and FIFOs only; name a file", what, path,
				 S_ISBLK(st->st_mode) ? "block device" : "socket");
	if (is_input(st))
		return mvod_errf(err, errlen, -EEXIST, "%s %s is a file this run reads (its source, a "
				 "frame, times.txt, the calibration, the ground truth, the "
				 "configuration, or an LCM log it replays or reads speed from): "
				 "mvod never writes over its input; name another file", what, path);
	return 0;
}

/* The folder that will hold a new or replaced file must take a new name (temp+rename). */
static int folder_writable(const char *what, const char *path, const char *target, char *err,
			   size_t errlen)
{
	const char *slash = strrchr(target, '/');
	char dir[PATH_MAX];
	snprintf(dir, sizeof(dir), "%.*s", slash ? (int)(slash - target) + 1 : 1, slash ? target : ".");
	if (access(dir, W_OK) == 0)
		return 0;
	int ret = -errno;
	return mvod_errf(err, errlen, ret, "%s %s: cannot write in %s: %s", what, path, dir,
			 strerror(-ret));
}

/*
 * Where to write: what the path reaches through every link, magic ones too (/dev/stdout is
 * /proc/self/fd/1, whose link text "pipe:[N]" names no file), decides the kind. Only a regular
 * file, replaced by rename, needs its name resolved; the resolved name must be that file.
 */
static int find_target(const char *path, char *target, size_t len, struct stat *st, bool *exists)
{
	*exists = stat(path, st) == 0;
	if (!*exists && errno != ENOENT)
		return -errno;
	if (*exists && !S_ISREG(st->st_mode))
		return (size_t)snprintf(target, len, "%s", path) < len ? 0 : -ENAMETOOLONG;
	int ret = resolve(path, target, len);
	struct stat resolved;
	if (!ret && *exists && (stat(target, &resolved) != 0 || resolved.st_ino != st->st_ino ||
				resolved.st_dev != st->st_dev))
		ret = -ELOOP;
	return ret;
}

int mvod_output_check(const char *what, const char *path, char *target, size_t targetlen,
		      enum mvod_output_kind *kind, char *err, size_t errlen)
{
	enum mvod_output_kind k = MVOD_OUTPUT_NEW;
	struct stat st;
	bool exists;
	int ret = find_target(path, target, targetlen, &st, &exists);
	if (ret == -ELOOP || ret == -ENAMETOOLONG)
		return mvod_errf(err, errlen, ret, "%s %s: cannot follow the symlink: %s", what, path,
				 strerror(-ret));
	if (ret)
		return mvod_errf(err, errlen, ret, "%s %s: %s", what, path, strerror(-ret));
	if (exists)
		ret = kind_of(what, path, &st, &k, err, errlen);
	if (!ret && (k == MVOD_OUTPUT_NEW || k == MVOD_OUTPUT_REGULAR))
		ret = folder_writable(what, path, target, err, errlen);
	if (kind)
		*kind = k;
	return ret;
}

/* --- stream outputs --- */

/* Stream outputs open now, read by signal handlers. */
static volatile sig_atomic_t streams_open;

bool mvod_outputs_open(void)
{
	return streams_open > 0;
}

struct mvod_output {
	int fd;
	int error;             /* the first failure, returned again at close */
	bool regular;          /* a file: locked, truncated, cut back, fsynced */
	bool truncate_pending; /* the run before's records stay until this run writes one */
	bool created;          /* by this open: removed again if no record ever came */
	char *what, *path;     /* in storage, for reopening and messages */
	char target[PATH_MAX]; /* the file path resolved to */
	char storage[];
};

static int open_failed(const char *what, const char *path, int e, char *err, size_t errlen)
{
	if (e == ENXIO)
		return mvod_errf(err, errlen, -e, "%s %s is a FIFO that no process reads: start the "
				 "reader first (mvod does not wait for one)", what, path);
	if (e == EWOULDBLOCK)
		return mvod_errf(err, errlen, -e, "%s %s is locked by another process writing it "
				 "(another mvod?): stop that one or name another file", what, path);
	return mvod_errf(err, errlen, -e, "%s %s: cannot open: %s", what, path, strerror(e));
}

/*
 * O_APPEND: after the deferred truncation, and after a cut-back, writes land at the end. A FIFO
 * stays non-blocking: a record up to PIPE_BUF goes in whole or fails with EAGAIN, so a reader
 * that stops reading is a write failure, never a loop stuck without a watchdog ping.
 */
static int open_locked(const char *what, const char *path, struct mvod_output *o, char *err,
		       size_t errlen)
{
	enum mvod_output_kind k;
	int ret = mvod_output_check(what, path, o->target, sizeof(o->target), &k, err, errlen);
	if (ret)
		return ret;
	o->regular = k == MVOD_OUTPUT_NEW || k == MVOD_OUTPUT_REGULAR;
	int flags = O_WRONLY | O_CLOEXEC | O_NOCTTY | (k == MVOD_OUTPUT_FIFO ? O_NONBLOCK : 0) |
		    (o->regular ? O_APPEND : 0);
	int *fd = &o->fd;
	/* O_EXCL first: a file that was not there is known as ours, to remove if left empty. */
	*fd = o->regular ? open(o->target, flags | O_CREAT | O_EXCL, 0644) : -1;
	o->created = *fd >= 0;
	if (*fd < 0)
		*fd = open(o->target, flags, 0644);
	if (*fd < 0)
		return open_failed(what, path, errno, err, errlen);
	if (o->regular && flock(*fd, LOCK_EX | LOCK_NB) != 0) {
		int e = errno;
		if (o->created)
			unlink(o->target);
		close(*fd);
		return open_failed(what, path, e, err, errlen);
	}
	return 0;
}

int mvod_output_open(const char *what, const char *path, struct mvod_output **out, char *err,
		     size_t errlen)
{
	size_t wl = strlen(what) + 1, pl = strlen(path) + 1;
	struct mvod_output *o = calloc(1, sizeof(*o) + wl + pl);
	if (!o)
		return mvod_errf(err, errlen, -ENOMEM, "%s %s: out of memory", what, path);
	o->what = memcpy(o->storage, what, wl);
	o->path = memcpy(o->storage + wl, path, pl);
	int ret = open_locked(what, path, o, err, errlen);
	if (ret) {
		free(o);
		return ret;
	}
	o->truncate_pending = o->regular;
	streams_open++;
	*out = o;
	return 0;
}

static int keep_error(struct mvod_output *o, int ret)
{
	if (ret && !o->error)
		o->error = ret;
	return ret;
}

int mvod_output_write(struct mvod_output *o, const void *buf, size_t len)
{
	if (o->truncate_pending && ftruncate(o->fd, 0) != 0)
		return keep_error(o, -errno);
	o->truncate_pending = false;
	ssize_t n;
	do
		n = write(o->fd, buf, len);
	while (n < 0 && errno == EINTR);
	int ret = n < 0 ? -errno : (size_t)n != len ? -ENOSPC : 0;
	struct stat st;
	/* A short write on a full disk: cut the partial record so the file stays parseable. */
	if (n > 0 && (size_t)n != len && o->regular &&
	    (fstat(o->fd, &st) != 0 || ftruncate(o->fd, st.st_size - n) != 0))
		ret = -errno;
	return keep_error(o, ret);
}

/* fsync where it means something: a device or FIFO says EINVAL, and that is no failure. */
static int sync_close(int fd)
{
	int ret = fsync(fd) != 0 && errno != EINVAL && errno != EROFS ? -errno : 0;
	if (close(fd) != 0 && !ret)
		ret = -errno;
	return ret;
}

int mvod_output_reopen(struct mvod_output *o, char *err, size_t errlen)
{
	struct stat now, open_st;
	/* Not rotated away: a second lock of our own file would fail; nothing to do. */
	if (stat(o->path, &now) == 0 && fstat(o->fd, &open_st) == 0 && now.st_dev == open_st.st_dev &&
	    now.st_ino == open_st.st_ino)
		return 0;
	struct mvod_output next = {.what = o->what, .path = o->path};
	int ret = open_locked(o->what, o->path, &next, err, errlen);
	if (ret)
		return ret;
	/* The file rotated away is complete on disk before its successor gets a record. */
	keep_error(o, sync_close(o->fd));
	o->fd = next.fd;
	o->regular = next.regular;
	o->truncate_pending = o->created = false;
	memcpy(o->target, next.target, sizeof(o->target));
	return 0;
}

int mvod_output_close(struct mvod_output *o)
{
	if (!o)
		return 0;
	/* A start that failed, or a run without a record, leaves no empty file it made. */
	if (o->created && o->truncate_pending)
		unlink(o->target);
	int ret = sync_close(o->fd);
	ret = o->error ? o->error : ret;
	free(o);
	streams_open--;
	return ret;
}
