/*
 * file:PATH[?realtime=1], any video FFmpeg reads, decoded to grey by video.c. realtime=1
 * hands frames out no faster than their media times, as a camera would, so that the live path
 * (capture thread, mailbox, dropped frames) runs without one.
 */
#include "capture/backends.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "capture/image_header.h"
#include "capture/uri.h"
#include "capture/video.h"
#include "util/clock.h"
#include "util/output.h"

/*
 * Containers without a frame index (Matroska, AVI) have their frame count estimated from the
 * file's duration times the nominal rate: for a variable-rate file, many more frames than it
 * holds. So a stream is broken only when it stops both short of that count and, by its own
 * timestamps, more than this much before the duration (which may cover the audio too).
 */
#define END_SLACK_S 0.5

/* A realtime read waits at most this long before answering "no frame yet", to stay stoppable. */
#define PACE_SLICE_US 100000

struct file_source {
	struct mvod_video *video;
	struct mvod_source_info info;
	int64_t next;      /* index of the next frame */
	int64_t last_us;   /* time of the previous frame */
	int64_t period_us; /* nominal frame period */
	int64_t short_of;  /* a stream ending before this many frames may be broken; <0 = unknown */
	int64_t end_us;    /* media time the duration reaches; -1 = unknown */
	char path[4096];
	bool realtime;
	bool pending;          /* held is decoded and waits for its time */
	struct mvod_frame held;
	int64_t wall0_us;      /* monotonic time the first frame was handed out */
	int64_t media0_us;     /* its media time */
};

static int take_param(void *ctx, const char *key, const char *value, char *err, size_t errlen)
{
	struct file_source *fs = ctx;
	if (strcmp(key, "realtime") != 0)
		return mvod_uri_unknown(key, "realtime", err, errlen);
	long on;
	int ret = mvod_uri_int(key, value, 0, 1, &on, err, errlen);
	fs->realtime = on;
	return ret;
}

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

static int file_open(void *priv, const char *location, char *err, size_t errlen)
{
	struct file_source *fs = priv;
	const char *path = fs->path;
	int ret = mvod_uri_parse(location, fs->path, sizeof(fs->path), take_param, fs, err, errlen);
	if (ret == 0)
		ret = check_file(path, err, errlen);
	/* The video is an input: no output of this process may be it (util/output.h). */
	if (ret == 0 && (ret = mvod_input_note(path)) != 0)
		mvod_errf(err, errlen, ret, "%s: %s", path, strerror(-ret));
	if (ret < 0)
		return ret;
	ret = mvod_video_open(path, &fs->video);
	if (ret == -ENODATA)
		return mvod_errf(err, errlen, ret, "video %s holds no frame", path);
	if (ret == -E2BIG)
		return mvod_errf(err, errlen, ret, "video %s: its frames are larger than the %lld "
				 "pixels (8192x8192) of any frame mvod takes", path,
				 (long long)MVOD_FRAME_MAX_PIXELS);
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
	fs->end_us = fs->info.fps > 0 && fs->info.frames > 0
			     ? llround((double)fs->info.frames * 1e6 / fs->info.fps) : -1;
	fs->info.live = fs->realtime;
	return 0;
fail:
	mvod_video_close(fs->video);
	return ret;
}

/* The decoder ran dry: the normal end, or -EIO when the file broke off before it. */
static int stream_end(const struct file_source *fs)
{
	int64_t last_us = fs->next ? fs->last_us : -fs->period_us;
	bool short_of_count = fs->next < fs->short_of;
	bool short_of_time = fs->end_us >= 0 &&
			     last_us + fs->period_us < fs->end_us - (int64_t)(END_SLACK_S * 1e6);
	return short_of_count && short_of_time ? -EIO : -ENODATA;
}

static int decode_next(struct file_source *fs, struct mvod_frame *frame)
{
	int64_t media_us = 0;
	int ret = mvod_video_read(fs->video, &frame->img, &media_us);
	if (ret == -ENODATA)
		return stream_end(fs);
	if (ret < 0 && ret != -EMSGSIZE)
		return ret;
	frame->index = fs->next++;
	/*
	 * A time that does not advance (a container without times gives 0 for every frame) is
	 * taken one period after the last.
	 */
	bool advances = frame->index == 0 || media_us > fs->last_us;
	frame->utime = advances ? media_us : fs->last_us + fs->period_us;
	fs->last_us = frame->utime;
	if (ret == 0)
		return 0;
	/* Not the stream's size: the queue's letters hold that size, and VO wants one size. */
	frame->bad = MVOD_BAD_SIZE;
	return -EINVAL;
}

/* The held frame once its media time has come, measured from the first frame's. */
static int paced_read(struct file_source *fs, struct mvod_frame *frame)
{
	if (!fs->pending) {
		int ret = decode_next(fs, &fs->held);
		if (ret == -EINVAL)
			*frame = fs->held; /* which frame was bad, and why */
		if (ret < 0)
			return ret;
		fs->pending = true;
		if (fs->held.index == 0) {
			fs->wall0_us = mvod_now_us();
			fs->media0_us = fs->held.utime;
		}
	}
	int64_t wait = fs->wall0_us + (fs->held.utime - fs->media0_us) - mvod_now_us();
	if (wait > PACE_SLICE_US) {
		usleep(PACE_SLICE_US);
		return -EAGAIN;
	}
	if (wait > 0)
		usleep((useconds_t)wait);
	*frame = fs->held;
	fs->pending = false;
	return 0;
}

static int file_read(void *priv, struct mvod_frame *frame, const struct mvod_image *into)
{
	(void)into; /* FFmpeg decodes into its own buffer; capture.c copies it into the letter */
	struct file_source *fs = priv;
	return fs->realtime ? paced_read(fs, frame) : decode_next(fs, frame);
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
