/*
 * The V4L2 backend's door to the kernel, as v4l-utils' struct v4l_fd: every system call the
 * backend makes goes through these pointers, so that tests can put a fake device behind them.
 * Each behaves as its libc namesake (-1 with errno on failure).
 */
#ifndef MVOD_CAPTURE_V4L2_H
#define MVOD_CAPTURE_V4L2_H

#include <poll.h>
#include <stdio.h>
#include <stdint.h>
#include <sys/types.h>

#include "capture/camfmt.h"

struct mvod_v4l2_io {
	int (*open)(const char *path, int flags);
	int (*close)(int fd);
	int (*ioctl)(int fd, unsigned long request, void *arg);
	void *(*mmap)(void *addr, size_t len, int prot, int flags, int fd, off_t offset);
	int (*munmap)(void *addr, size_t len);
	int (*poll)(struct pollfd *fds, nfds_t nfds, int timeout_ms);
};

/* The kernel's. */
extern const struct mvod_v4l2_io mvod_v4l2_libc_io;
/* What every v4l2: source opens and --list-cameras probes with; tests point it at a fake. */
extern const struct mvod_v4l2_io *mvod_v4l2_io;

/* ioctl through io, retried while a signal interrupts it. 0 or -errno. */
int mvod_v4l2_xioctl(const struct mvod_v4l2_io *io, int fd, unsigned long request, void *arg);

/*
 * Prints every V4L2 capture device among /dev/video0../dev/video63 (name, driver, bus, and each
 * format mvod reads with its sizes and rates), each with its --source URI. Returns how many.
 */
int mvod_v4l2_list(FILE *out);

#endif
