/* kitti:SEQDIR, the KITTI odometry layout: image_0/, times.txt, calib.txt (P0). */
#include "capture/backends.h"

#include <assert.h>
#include <limits.h>
#include <stddef.h>

#include "capture/images.h"

struct kitti {
	struct mvod_images images; /* first, so the images ops work on a kitti priv as is */
	struct mvod_camera cam;    /* P0, with the size of the images */
};

static_assert(offsetof(struct kitti, images) == 0, "the images ops take the kitti priv");

static int kitti_open(void *priv, const char *seqdir, char *err, size_t errlen)
{
	struct kitti *k = priv;
	char calib[PATH_MAX], image_dir[PATH_MAX], times[PATH_MAX];
	int ret = mvod_capture_path(calib, sizeof(calib), seqdir, "calib.txt", err, errlen);
	if (!ret)
		ret = mvod_capture_path(image_dir, sizeof(image_dir), seqdir, "image_0", err, errlen);
	if (!ret)
		ret = mvod_capture_path(times, sizeof(times), seqdir, "times.txt", err, errlen);
	/* The calibration first: a sequence without one fails before any image is decoded. */
	if (!ret)
		ret = mvod_calib_load_kitti(calib, &k->cam, err, errlen);
	if (!ret)
		ret = mvod_images_open(&k->images, image_dir, times, err, errlen);
	if (ret < 0)
		return ret;
	k->cam.width = k->images.info.width;
	k->cam.height = k->images.info.height;
	return 0;
}

static int kitti_camera(void *priv, struct mvod_camera *cam)
{
	const struct kitti *k = priv;
	*cam = k->cam;
	return 0;
}

const struct mvod_source_ops mvod_source_kitti_ops = {
	.scheme = "kitti",
	.summary = "kitti:SEQDIR  KITTI odometry sequence: image_0/, times.txt, calib.txt (P0)",
	.priv_size = sizeof(struct kitti),
	.open = kitti_open,
	.read = mvod_images_read,
	.info = mvod_images_info,
	.camera = kitti_camera,
	.close = mvod_images_close,
};
