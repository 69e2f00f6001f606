/*
 * Frame sources, chosen by URI scheme (file:, images:, kitti:, euroc:, tum:, v4l2:, libcamera:). Each
 * backend is a const struct mvod_source_ops, the way LCM picks a provider from its URL.
 */
#ifndef MVOD_CAPTURE_H
#define MVOD_CAPTURE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdint.h>

#include "mvod/calib.h"
#include "mvod/image.h"
#include "mvod/traj.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Why a read gave -EINVAL (one bad frame, skipped); the run's summary counts each apart. */
enum mvod_bad_frame {
	MVOD_BAD_UNREADABLE, /* the file could not be read (I/O error, permissions, vanished) */
	MVOD_BAD_CORRUPT,    /* not an image, or corrupt */
	MVOD_BAD_TOO_LARGE,  /* a file larger than any frame of the sequence's size can be */
	MVOD_BAD_SIZE,       /* of another size than the first frame */
	MVOD_BAD_COUNT
};
/* "corrupt", "of another size", ...: for messages and the summary. */
const char *mvod_bad_frame_name(enum mvod_bad_frame why);

struct mvod_frame {
	struct mvod_image img; /* borrowed from the source: valid until the next read or close */
	int64_t utime;         /* source clock (media time, times.txt), microseconds */
	/*
	 * When the source delivered it (its read returned), CLOCK_MONOTONIC microseconds: where
	 * the capture-to-publish latency starts.
	 */
	int64_t delivered_us;
	int64_t index;         /* 0-based frame number in the source */
	enum mvod_bad_frame bad; /* why, when the read gave -EINVAL */
	/*
	 * From the capture thread of a live source: the frames before this one that could not
	 * be decoded, since the start, by reason. They leave gaps in index but are no dropped
	 * frames: they are counted apart (the summary's skipped, FAULT_FRAME_UNREADABLE).
	 */
	int64_t bad_before[MVOD_BAD_COUNT];
};

struct mvod_source_info {
	int width, height; /* pixels of every frame the source will deliver */
	double fps;        /* nominal rate; 0 when unknown */
	int64_t frames;    /* total frames when known, else -1 */
	/*
	 * Frames come at their own pace (a camera, file:?realtime=1): read them on a capture
	 * thread and drop what processing cannot keep up with. Otherwise every frame is processed.
	 */
	bool live;
	/* Lens focus position the camera was locked at (device units); NaN when unknown. */
	double focus;
	/*
	 * The frame times are made up, not read (an image folder without times.txt: 10 Hz). mvod
	 * run warns, since speeds and the trajectory's times follow them; calibration does not
	 * use times and says nothing.
	 */
	bool times_assumed;
	/* utime is on CLOCK_MONOTONIC (a camera's buffer time), so it can go out as real time. */
	bool monotonic;
};

struct mvod_source_ops {
	const char *scheme;   /* URI scheme without the colon, e.g. "images" */
	const char *summary;  /* one line for --help */
	size_t priv_size;     /* bytes of backend state, zeroed before open */
	/* location is the URI without "scheme:". Returns 0 or -errno with a reason in err. */
	int (*open)(void *priv, const char *location, char *err, size_t errlen);
	/*
	 * 0 = a frame, -ENODATA = end of stream, -EAGAIN = no frame yet, -EINVAL = one bad frame
	 * (skipped; frame->index and frame->bad say which and why), -ENODEV = the device is gone (a live source is reopened), other -errno =
	 * failure. into is NULL or a grey image of the source's size, borrowed for the call: a
	 * source that converts camera buffers writes the frame there instead of into its own
	 * buffer, and frame->img views it. Sources that decode elsewhere ignore it.
	 */
	int (*read)(void *priv, struct mvod_frame *frame, const struct mvod_image *into);
	void (*info)(void *priv, struct mvod_source_info *info);
	/* Intrinsics the source carries (KITTI calib.txt); -ENOENT when it has none. May be NULL. */
	int (*camera)(void *priv, struct mvod_camera *cam);
	/*
	 * Ground truth the dataset carries (see mvod_source_ground_truth); -ENOENT when it has
	 * none. May be NULL.
	 */
	int (*ground_truth)(void *priv, struct mvod_traj *gt, char *from, size_t fromlen, char *err,
			    size_t errlen);
	void (*close)(void *priv);
};

struct mvod_source;

/* Opens a source from a URI such as "file:clip.mkv". -EPROTONOSUPPORT for an unknown scheme. */
int mvod_source_open(const char *uri, struct mvod_source **out, char *err, size_t errlen);
int mvod_source_read(struct mvod_source *src, struct mvod_frame *frame);
/*
 * The same, offering into (see mvod_source_ops.read) to save a copy: frame->img.data ==
 * into->data when the source converted into it.
 */
int mvod_source_read_into(struct mvod_source *src, struct mvod_frame *frame,
			  const struct mvod_image *into);
void mvod_source_info(struct mvod_source *src, struct mvod_source_info *info);
int mvod_source_camera(struct mvod_source *src, struct mvod_camera *cam);
/*
 * The ground truth of a dataset source, for a run given no --gt: camera-to-world poses of this
 * source's camera, world = the camera frame of the first frame that has a pose (mvod's own
 * world), metres; KITTI's poses/NN.txt as it is (one pose per frame), EuRoC and TUM resampled
 * at the frames' own times (TUM format, t = utime / 1e6, so that a frame finds its pose
 * exactly). The file it came from goes into from. -ENOENT when the source has none (err
 * untouched); other -errno with a reason naming the file in err. gt is freed with
 * mvod_traj_free.
 */
int mvod_source_ground_truth(struct mvod_source *src, struct mvod_traj *gt, char *from,
			     size_t fromlen, char *err, size_t errlen);
/* True when uri's scheme may carry its own ground truth (kitti:, euroc:, tum:). */
bool mvod_source_may_have_gt(const char *uri);
/* Closes and frees; NULL is a no-op. */
void mvod_source_close(struct mvod_source *src);

/* The registered backends, NULL-terminated (for --help and tests). */
extern const struct mvod_source_ops *const mvod_source_backends[];

/*
 * Prints the cameras attached (V4L2 capture devices with their formats, sizes and rates;
 * libcamera cameras), each with the --source URI that opens it. Returns how many.
 */
int mvod_capture_list_cameras(FILE *out);

/*
 * A source read on its own thread, so that decoding overlaps processing on another core.
 * Live: the newest frame waits in a single-slot mailbox of preallocated buffers; a frame that
 * a newer one replaces before it was taken is dropped (it leaves a gap in the frame indices
 * the consumer sees). A source whose device is gone (-ENODEV: a camera unplugged) is closed,
 * reported once, and reopened from its URI with backoff, 0.5 s doubling to 8 s; frame indices
 * go on from where they were. Not live (files, images, datasets): every frame, bad ones
 * included, waits in a bounded queue of preallocated buffers, in order; the thread waits for
 * room, and never drops one.
 */
struct mvod_capture;

/* On success owns src (open) and reads it; uri reopens a live one after a failure. */
int mvod_capture_start(struct mvod_source *src, const char *uri, struct mvod_capture **out);
/*
 * The next frame (live: the newest), waiting up to timeout_ms. 0 with the frame (valid until
 * the next call) and *epoch, the number of times the source has come back before it; -EINVAL
 * for one bad frame of a source that is not live (frame->index and frame->bad say which and
 * why; skip it; a live source's are counted in the next frame's bad_before); -EAGAIN when
 * none came; once every frame was taken, -ENODATA when the source
 * ended or its -errno when it failed.
 */
int mvod_capture_next(struct mvod_capture *c, int timeout_ms, struct mvod_frame *frame,
		      int *epoch);
/* The source is down and being reopened. */
bool mvod_capture_down(struct mvod_capture *c);
/* Stops the thread promptly (even while reopening), closes the source, frees. NULL: no-op. */
void mvod_capture_stop(struct mvod_capture *c);

#ifdef __cplusplus
}
#endif

#endif
