/* mvod --list-cameras for V4L2: what each capture node offers, and the URI that opens it. */
#include "capture/v4l2.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <string.h>

#include <linux/videodev2.h>

#define MAX_NODES 64

/* What the --source example of a node asks for: its first size and rate mvod reads. */
struct example {
	int format; /* enum mvod_camfmt, or -1 before one is found */
	uint32_t w, h;
	double fps;
};

/* The rates of one discrete size, as " @ 30, 15 fps"; returns the first (0 when none). */
static double print_rates(const struct mvod_v4l2_io *io, int fd, uint32_t fourcc, uint32_t w,
			  uint32_t h, FILE *out)
{
	struct v4l2_frmivalenum fi = {.pixel_format = fourcc, .width = w, .height = h};
	double first = 0;
	for (; mvod_v4l2_xioctl(io, fd, VIDIOC_ENUM_FRAMEINTERVALS, &fi) == 0; fi.index++) {
		if (fi.type != V4L2_FRMIVAL_TYPE_DISCRETE) {
			fprintf(out, " @ %.4g to %.4g fps", (double)fi.stepwise.max.denominator /
				fi.stepwise.max.numerator, (double)fi.stepwise.min.denominator /
				fi.stepwise.min.numerator);
			return 0;
		}
		double fps = (double)fi.discrete.denominator / fi.discrete.numerator;
		first = fi.index ? first : fps;
		fprintf(out, "%s%.4g", fi.index ? ", " : " @ ", fps);
	}
	if (fi.index)
		fprintf(out, " fps");
	return first;
}

/* Sizes and rates of one format; ex (when not NULL) takes the first size and its first rate. */
static void print_sizes(const struct mvod_v4l2_io *io, int fd, uint32_t fourcc, FILE *out,
			struct example *ex)
{
	struct v4l2_frmsizeenum fs = {.pixel_format = fourcc};
	for (; mvod_v4l2_xioctl(io, fd, VIDIOC_ENUM_FRAMESIZES, &fs) == 0; fs.index++) {
		if (fs.type != V4L2_FRMSIZE_TYPE_DISCRETE) {
			fprintf(out, "      %ux%u to %ux%u\n", fs.stepwise.min_width,
				fs.stepwise.min_height, fs.stepwise.max_width, fs.stepwise.max_height);
			return;
		}
		uint32_t w = fs.discrete.width, h = fs.discrete.height;
		fprintf(out, "      %ux%u", w, h);
		double fps = print_rates(io, fd, fourcc, w, h, out);
		fprintf(out, "\n");
		if (ex && ex->w == 0)
			*ex = (struct example){ex->format, w, h, fps};
	}
}

static void print_example(const char *path, const struct example *ex, FILE *out)
{
	if (ex->format < 0) {
		fprintf(out, "    (none of the formats mvod reads: %s)\n", mvod_camfmt_known);
		return;
	}
	fprintf(out, "    --source 'v4l2:%s?", path);
	if (ex->w)
		fprintf(out, "width=%u&height=%u&", ex->w, ex->h);
	if (ex->fps > 0)
		fprintf(out, "fps=%.4g&", ex->fps);
	fprintf(out, "format=%s'\n", mvod_camfmt_name((enum mvod_camfmt)ex->format));
}

/* Every format of the node; the example uses the first one mvod reads. */
static void print_formats(const struct mvod_v4l2_io *io, int fd, const char *path, FILE *out)
{
	struct v4l2_fmtdesc d = {.type = V4L2_BUF_TYPE_VIDEO_CAPTURE};
	struct example ex = {.format = -1};
	for (; mvod_v4l2_xioctl(io, fd, VIDIOC_ENUM_FMT, &d) == 0; d.index++) {
		enum mvod_camfmt f;
		bool ours = mvod_camfmt_of_fourcc(d.pixelformat, MVOD_CAMFMT_V4L2, &f) == 0;
		fprintf(out, "    %.4s (%s)%s\n", (const char *)&d.pixelformat,
			(const char *)d.description, ours ? "" : ": mvod does not read this format");
		if (!ours)
			continue;
		bool first = ex.format < 0;
		if (first)
			ex.format = (int)f;
		print_sizes(io, fd, d.pixelformat, out, first ? &ex : NULL);
	}
	print_example(path, &ex, out);
}

/* 1 when path is a capture node (and was printed), else 0. */
static int list_node(const struct mvod_v4l2_io *io, const char *path, FILE *out)
{
	int fd = io->open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0)
		return 0;
	struct v4l2_capability cap = {0};
	int ret = mvod_v4l2_xioctl(io, fd, VIDIOC_QUERYCAP, &cap);
	uint32_t caps = cap.capabilities & V4L2_CAP_DEVICE_CAPS ? cap.device_caps : cap.capabilities;
	int capture = !ret && (caps & V4L2_CAP_VIDEO_CAPTURE) && (caps & V4L2_CAP_STREAMING);
	if (capture) {
		fprintf(out, "v4l2:%s  %s (driver %s, bus %s)\n", path, (const char *)cap.card,
			(const char *)cap.driver, (const char *)cap.bus_info);
		print_formats(io, fd, path, out);
	}
	io->close(fd);
	return capture;
}

int mvod_v4l2_list(FILE *out)
{
	int n = 0;
	for (int i = 0; i < MAX_NODES; i++) {
		char path[32];
		snprintf(path, sizeof(path), "/dev/video%d", i);
		n += list_node(mvod_v4l2_io, path, out);
	}
	return n;
}
