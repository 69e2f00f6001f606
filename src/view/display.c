/*
 * Whether the display named in the environment answers. OpenCV's Qt backend aborts the whole
 * process when it cannot connect, so the viewer asks first and can say what to do instead.
 */
#include "mvod/view.h"

#include <errno.h>
#include <netdb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "util/errbuf.h"

/* X11 listens on TCP port 6000 + display number. */
#define X11_TCP_BASE 6000

static int connect_unix(const char *path)
{
	struct sockaddr_un sa = {.sun_family = AF_UNIX};
	if (strlen(path) >= sizeof(sa.sun_path))
		return -ENAMETOOLONG;
	strcpy(sa.sun_path, path);
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
	if (fd < 0)
		return -errno;
	int ret = connect(fd, (struct sockaddr *)&sa, sizeof(sa)) ? -errno : 0;
	close(fd);
	return ret;
}

static int connect_tcp(const char *host, int port)
{
	char service[16];
	snprintf(service, sizeof(service), "%d", port);
	struct addrinfo hints = {.ai_socktype = SOCK_STREAM}, *res;
	if (getaddrinfo(host, service, &hints, &res))
		return -EHOSTUNREACH;
	int ret = -ECONNREFUSED;
	for (struct addrinfo *a = res; a && ret; a = a->ai_next) {
		int fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
		if (fd < 0)
			continue;
		ret = connect(fd, a->ai_addr, a->ai_addrlen) ? -errno : 0;
		close(fd);
	}
	freeaddrinfo(res);
	return ret;
}

/* DISPLAY is [host]:N[.screen]: no host (or "unix") is the local socket of display N. */
static int check_x11(const char *display, char *err, size_t errlen)
{
	const char *colon = strrchr(display, ':');
	if (!colon || colon[1] < '0' || colon[1] > '9')
		return mvod_errf(err, errlen, -EINVAL, "DISPLAY=%s is not [host]:N", display);
	int n = atoi(colon + 1);
	char host[256], path[64];
	snprintf(host, sizeof(host), "%.*s", (int)(colon - display), display);
	int ret;
	if (!host[0] || strcmp(host, "unix") == 0) {
		snprintf(path, sizeof(path), "/tmp/.X11-unix/X%d", n);
		ret = connect_unix(path);
	} else {
		ret = connect_tcp(host, X11_TCP_BASE + n);
	}
	return ret ? mvod_errf(err, errlen, ret, "cannot reach the X display DISPLAY=%s: %s",
			       display, strerror(-ret))
		   : 0;
}

static int check_wayland(const char *name, char *err, size_t errlen)
{
	const char *runtime = getenv("XDG_RUNTIME_DIR");
	char path[512];
	if (name[0] != '/' && !runtime)
		return mvod_errf(err, errlen, -ENOENT, "WAYLAND_DISPLAY=%s but XDG_RUNTIME_DIR is unset",
				 name);
	snprintf(path, sizeof(path), "%s%s%s", name[0] == '/' ? "" : runtime,
		 name[0] == '/' ? "" : "/", name);
	int ret = connect_unix(path);
	return ret ? mvod_errf(err, errlen, ret, "cannot reach the Wayland display %s: %s", path,
			       strerror(-ret))
		   : 0;
}

int mvod_view_display_check(char *err, size_t errlen)
{
	const char *x = getenv("DISPLAY"), *w = getenv("WAYLAND_DISPLAY");
	if (x && *x)
		return check_x11(x, err, errlen);
	if (w && *w)
		return check_wayland(w, err, errlen);
	return mvod_errf(err, errlen, -ENXIO, "no display (DISPLAY and WAYLAND_DISPLAY are unset)");
}
