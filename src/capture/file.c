/* file:PATH, any video FFmpeg reads, decoded through the OpenCV shim. */
#include "capture/backends.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "capture/video_shim.h"

/*
 * Containers without a frame index (Matroska, AVI) have their frame count estimated from the
 * file's duration, which covers the audio too; a stream that stops within this much of the
 * count is taken as a normal end, one that stops earlier as broken.
 */
#define END_SLACK_S 0.5

struct file_source {
	struct mvod_video *video;
	struct mvod_source_info info;
	int64_t next;      /* index of the next frame */
	int64_t last_us;   /* time of the previous frame */
	int64_t period_us; /* nominal frame period */
	int64_t short_of;  /* a stream ending before this many frames is broken; <0 = unknown */
};

/* A readable regular file, or one line saying what is wrong. */
static int check_file(const char *path, char *err, size_t errlen)
{
	struct stat st;
	int ret = stat(path, &st) < 0 || access(path, R_OK) < 0 ? -errno : 0;
	if (ret == -ENOENT)
		return mvod_errf(err, errlen, ret, "no such file: %s", path);
	if (ret < 0)
		return mvod_errf(err, errlen, ret, "cannot read %s: %s", path,
					 strerror(-ret));
	if (S_ISDIR(st.st_mode))
		return mvod_errf(err, errlen, -EISDIR, "%s is a directory: for an image "
					 "sequence write images:%s", path, path);
	return 0;
}

static int file_open(void *priv, const char *path, char *err, size_t errlen)
{
	struct file_source *fs = priv;
	int ret = check_file(path, err, errlen);
	if (ret < 0)
		return ret;
	ret = mvod_video_open(path, &fs->video);
	if (ret < 0)
		return mvod_errf(err, errlen, ret, "cannot decode video %s: FFmpeg cannot "
					 "read it (corrupt, or not a video)", path);
	mvod_video_props(fs->video, &fs->info);
	if (fs->info.width <= 0 || fs->info.height <= 0) {
		ret = mvod_errf(err, errlen, -EINVAL, "cannot decode video %s: no frame "
					"size in the stream", path);
		goto fail;
	}
	/* Any strictly increasing time will do when the rate is unknown. */
	fs->period_us = fs->info.fps > 0 ? llround(1e6 / fs->info.fps) : 1;
	fs->short_of = fs->info.frames - (int64_t)ceil(END_SLACK_S * fs->info.fps);
	return 0;
fail:
	mvod_video_close(fs->video);
	return ret;
}

static int file_read(void *priv, struct mvod_frame *frame)
{
	struct file_source *fs = priv;
	int64_t media_us = 0;
	int ret = mvod_video_read(fs->video, &frame->img, &media_us);
	if (ret == -ENODATA && fs->next < fs->short_of)
		return -EIO;
	if (ret < 0)
		return ret;
	frame->index = fs->next++;
	/*
	 * OpenCV reports 0 ms for the frames FFmpeg flushes out of a B-frame decoder at the end
	 * of the stream; a time that does not advance is taken one period after the last.
	 */
	bool advances = frame->index == 0 || media_us > fs->last_us;
	frame->utime = advances ? media_us : fs->last_us + fs->period_us;
	fs->last_us = frame->utime;
	return 0;
}

static void file_info(void *priv, struct mvod_source_info *info)
{
	const struct file_source *fs = priv;
	*info = fs->info;
}

static void file_close(void *priv)
{
	struct file_source *fs = priv;
	mvod_video_close(fs->video);
}

const struct mvod_source_ops mvod_source_file_ops = {
	.scheme = "file",
	.summary = "file:PATH  a video file (anything FFmpeg reads; timestamps from the media)",
	.priv_size = sizeof(struct file_source),
	.open = file_open,
	.read = file_read,
	.info = file_info,
	.camera = NULL,
	.close = file_close,
};
