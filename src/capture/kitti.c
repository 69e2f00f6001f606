/* kitti:SEQDIR, the KITTI odometry layout: image_0/, times.txt, calib.txt (P0). */
#include "capture/backends.h"
#include "capture/path.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capture/images.h"

struct kitti {
	struct mvod_images images; /* first, so the images ops work on a kitti priv as is */
	struct mvod_camera cam;    /* P0, with the size of the images */
	char gt_path[PATH_MAX];    /* ROOT/poses/NN.txt for ROOT/sequences/NN, or "" */
};

static_assert(offsetof(struct kitti, images) == 0, "the images ops take the kitti priv");

/* SEQDIR = ROOT/sequences/NN: the ground truth is ROOT/poses/NN.txt, when it is there. */
static void find_poses(const char *seqdir, char *gt, size_t len)
{
	char real[PATH_MAX];
	gt[0] = '\0';
	if (!realpath(seqdir, real))
		return;
	char *nn = strrchr(real, '/');
	if (!nn || nn == real)
		return;
	*nn++ = '\0';
	char *sequences = strrchr(real, '/');
	if (!sequences || strcmp(sequences, "/sequences") != 0)
		return;
	*sequences = '\0';
	int n = snprintf(gt, len, "%s/poses/%s.txt", real, nn);
	if (n < 0 || (size_t)n >= len || access(gt, F_OK) != 0)
		gt[0] = '\0';
}

static int kitti_open(void *priv, const char *seqdir, char *err, size_t errlen)
{
	struct kitti *k = priv;
	char calib[PATH_MAX], image_dir[PATH_MAX], times[PATH_MAX];
	int ret = mvod_capture_path(calib, sizeof(calib), seqdir, "calib.txt", err, errlen);
	if (!ret)
		ret = mvod_capture_path(image_dir, sizeof(image_dir), seqdir, "image_0", err, errlen);
	if (!ret)
		ret = mvod_capture_path(times, sizeof(times), seqdir, "times.txt", err, errlen);
	/* A raw drive has image_00/ and no calib.txt: it is kitti-raw:'s. */
	char raw[PATH_MAX];
	if (!ret && access(calib, F_OK) != 0 &&
	    mvod_capture_path(raw, sizeof(raw), seqdir, "image_00/timestamps.txt", NULL, 0) == 0 &&
	    access(raw, F_OK) == 0)
		return mvod_errf(err, errlen, -EINVAL, "kitti:%s is a KITTI raw drive (image_00/, no "
				 "calib.txt): open it as kitti-raw:%s", seqdir, seqdir);
	/* The calibration first: a sequence without one fails before any image is decoded. */
	if (!ret)
		ret = mvod_calib_load_kitti(calib, &k->cam, err, errlen);
	if (!ret)
		ret = mvod_images_open(&k->images, image_dir, times, err, errlen);
	if (ret < 0)
		return ret;
	k->cam.width = k->images.info.width;
	k->cam.height = k->images.info.height;
	find_poses(seqdir, k->gt_path, sizeof(k->gt_path));
	return 0;
}

static int kitti_camera(void *priv, struct mvod_camera *cam)
{
	const struct kitti *k = priv;
	*cam = k->cam;
	return 0;
}

static int kitti_ground_truth(void *priv, struct mvod_traj *gt, char *from, size_t fromlen,
			      char *err, size_t errlen)
{
	const struct kitti *k = priv;
	if (!k->gt_path[0])
		return -ENOENT;
	snprintf(from, fromlen, "%s", k->gt_path);
	return mvod_traj_load(k->gt_path, gt, err, errlen);
}

const struct mvod_source_ops mvod_source_kitti_ops = {
	.scheme = "kitti",
	.summary = "kitti:SEQDIR  KITTI odometry sequence: image_0/, times.txt, calib.txt (P0); "
		   "ground truth from ../../poses/NN.txt",
	.priv_size = sizeof(struct kitti),
	.open = kitti_open,
	.read = mvod_images_read,
	.info = mvod_images_info,
	.camera = kitti_camera,
	.ground_truth = kitti_ground_truth,
	.close = mvod_images_close,
};
