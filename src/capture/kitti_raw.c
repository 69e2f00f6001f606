/*
 * kitti-raw:DRIVE, a synced and rectified drive of the KITTI raw data: frames from
 * image_00/data/NNNNNNNNNN.png at image_00/timestamps.txt's calendar times, camera 0's
 * rectified intrinsics and the IMU-to-camera extrinsics from the date's calibration files
 * (DRIVE/.., as downloaded, or DRIVE itself), and ground truth from oxts/data: the _sync
 * drive's packet NNNNNNNNNN is frame NNNNNNNNNN's (the devkit's synchronisation).
 */
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

#include "capture/dataset.h"
#include "capture/oxts.h"
#include "mvod/log.h"
#include "util/lines.h"

struct kitti_raw {
	struct mvod_dataset ds;  /* first, so that the dataset ops work on it as is */
	char drive[PATH_MAX];
	char calib[PATH_MAX];    /* the folder of calib_*.txt */
	struct mvod_pose cam_imu; /* T_cam0_imu */
};

static_assert(offsetof(struct kitti_raw, ds) == 0, "the dataset ops take the kitti-raw priv");

/* The calibration beside the drive (DATE/, as downloaded), else copied into it. */
static int find_calib(struct kitti_raw *k, char *err, size_t errlen)
{
	char real[PATH_MAX], probe[PATH_MAX];
	if (!realpath(k->drive, real))
		return mvod_errf(err, errlen, -errno, "kitti-raw:%s: %s", k->drive, strerror(errno));
	char *slash = strrchr(real, '/');
	*(slash == real ? slash + 1 : slash) = '\0';
	int ret = mvod_capture_path(probe, sizeof(probe), real, "calib_cam_to_cam.txt", err, errlen);
	snprintf(k->calib, sizeof(k->calib), "%s", ret || access(probe, F_OK) ? k->drive : real);
	return 0;
}

struct index {
	struct mvod_ds_frames frames;
	const char *path; /* image_00/timestamps.txt */
	char data[PATH_MAX]; /* image_00/data */
};

/* "2011-09-26 13:02:25.964389445": frame N of the drive is the Nth line's. */
static int add_stamp(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct index *x = ctx;
	const char *end;
	int64_t ns;
	if (mvod_ds_parse_calendar(line, &end, &ns) < 0 || end[strspn(end, " \t")])
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: \"%.40s\" is not a calendar "
				 "time \"YYYY-MM-DD HH:MM:SS.NNNNNNNNN\"", x->path, lineno, line);
	char name[32];
	snprintf(name, sizeof(name), "%010zu.png", x->frames.n);
	return mvod_ds_frames_add(&x->frames, x->path, lineno, x->data, name, ns, err, errlen);
}

/* The frames' size must be the rectified one: the unsynced "extract" download is not. */
static int check_size(const struct kitti_raw *k, char *err, size_t errlen)
{
	const struct mvod_source_info *i = &k->ds.images.info;
	if (i->width == k->ds.cam.width && i->height == k->ds.cam.height)
		return 0;
	return mvod_errf(err, errlen, -EINVAL, "%s: frames are %dx%d, but %s/calib_cam_to_cam.txt's "
			 "S_rect_00 says %dx%d: kitti-raw: reads the rectified _sync drives (an "
			 "unrectified \"extract\" drive has 1392x512 frames)", k->ds.index, i->width,
			 i->height, k->calib, k->ds.cam.width, k->ds.cam.height);
}

static int kitti_raw_open(void *priv, const char *drive, char *err, size_t errlen)
{
	struct kitti_raw *k = priv;
	struct mvod_dataset *ds = &k->ds;
	struct index x = {.path = ds->index};
	int n = snprintf(k->drive, sizeof(k->drive), "%s", drive);
	int ret = n < 0 || (size_t)n >= sizeof(k->drive)
			  ? mvod_errf(err, errlen, -ENAMETOOLONG, "path too long: %s", drive)
			  : find_calib(k, err, errlen);
	if (!ret)
		ret = mvod_capture_path(ds->index, sizeof(ds->index), drive,
					"image_00/timestamps.txt", err, errlen);
	if (!ret)
		ret = mvod_capture_path(x.data, sizeof(x.data), drive, "image_00/data", err, errlen);
	/* The camera first: a drive without one fails before any image is decoded. */
	if (!ret)
		ret = mvod_kitti_raw_calib(k->calib, &ds->cam, &k->cam_imu, err, errlen);
	if (!ret)
		ret = mvod_lines_each(ds->index, "KITTI raw timestamps.txt", add_stamp, &x, err,
				      errlen);
	if (ret) {
		mvod_ds_frames_free(&x.frames);
		return ret;
	}
	ds->has_cam = true;
	ret = mvod_ds_open_frames(ds, &x.frames, err, errlen);
	if (!ret && (ret = check_size(k, err, errlen)))
		mvod_ds_close(ds);
	if (!ret)
		LOG(INFO, "kitti-raw:%s: %zu frames of image_00/data at the times of %s; camera 0 "
			  "rectified (P_rect_00, S_rect_00 %dx%d) from %s/calib_cam_to_cam.txt", drive,
		    ds->images.n, ds->index, ds->cam.width, ds->cam.height, k->calib);
	return ret;
}

/* Frame i's camera pose in the OXTS world, T_w_imu T_cam0_imu^-1; scale set at frame 0. */
static int camera_at(const struct kitti_raw *k, size_t i, double *scale, struct mvod_pose *cam,
		     char *err, size_t errlen)
{
	char path[PATH_MAX];
	double packet[6];
	struct mvod_pose imu, imu_cam;
	int n = snprintf(path, sizeof(path), "%s/oxts/data/%010zu.txt", k->drive, i);
	if (n < 0 || (size_t)n >= sizeof(path))
		return mvod_errf(err, errlen, -ENAMETOOLONG, "path too long: %s/oxts", k->drive);
	int ret = mvod_oxts_read(path, packet, err, errlen);
	if (ret)
		return ret;
	if (i == 0)
		*scale = mvod_oxts_scale(packet[0]);
	mvod_oxts_pose(packet, *scale, &imu);
	/* The one check of every ground-truth pose (traj.h): near a pole the projection is not. */
	double rt[12];
	char reason[256];
	for (int r = 0; r < 3; r++) {
		memcpy(rt + 4 * r, imu.R + 3 * r, 3 * sizeof(double));
		rt[4 * r + 3] = imu.t[r];
	}
	if (mvod_pose_from_matrix(rt, &imu, reason, sizeof(reason)))
		return mvod_errf(err, errlen, -EINVAL, "%s line 1: %s", path, reason);
	mvod_pose_inverse(&k->cam_imu, &imu_cam);
	mvod_pose_compose(&imu, &imu_cam, cam);
	return 0;
}

/* Every frame's camera pose relative to frame 0's, t the frame's time (KITTI format: by index). */
static int kitti_raw_ground_truth(void *priv, struct mvod_traj *gt, char *from, size_t fromlen,
				  char *err, size_t errlen)
{
	const struct kitti_raw *k = priv;
	const size_t n = k->ds.images.n;
	char oxts[PATH_MAX];
	int ret = mvod_capture_path(oxts, sizeof(oxts), k->drive, "oxts/data", err, errlen);
	if (ret)
		return ret;
	if (access(oxts, F_OK) != 0)
		return -ENOENT;
	*gt = (struct mvod_traj){.format = MVOD_TRAJ_KITTI, .t = malloc(n * sizeof(*gt->t)),
				 .pose = malloc(n * sizeof(*gt->pose))};
	if (!gt->t || !gt->pose)
		ret = mvod_errf(err, errlen, -ENOMEM, "out of memory for %zu poses", n);
	double scale = 0;
	struct mvod_pose first_inv, cam;
	for (size_t i = 0; !ret && i < n; i++) {
		ret = camera_at(k, i, &scale, &cam, err, errlen);
		if (!ret && i == 0)
			mvod_pose_inverse(&cam, &first_inv);
		if (!ret)
			mvod_pose_compose(&first_inv, &cam, &gt->pose[i]);
		gt->t[i] = k->ds.images.times_us[i] / 1e6;
	}
	if (ret) {
		mvod_traj_free(gt);
		return ret;
	}
	mvod_pose_identity(&gt->pose[0]); /* exactly, not to rounding */
	gt->n = (int)n;
	snprintf(from, fromlen, "%s/NNNNNNNNNN.txt through %s/calib_imu_to_velo.txt, "
		 "calib_velo_to_cam.txt and calib_cam_to_cam.txt's R_rect_00", oxts, k->calib);
	return 0;
}

const struct mvod_source_ops mvod_source_kitti_raw_ops = {
	.scheme = "kitti-raw",
	.summary = "kitti-raw:DRIVE  KITTI raw _sync drive: image_00/data/, image_00/timestamps.txt, "
		   "the date's calib_*.txt beside it; ground truth from oxts/data/",
	.priv_size = sizeof(struct kitti_raw),
	.open = kitti_raw_open,
	.read = mvod_images_read,
	.info = mvod_images_info,
	.camera = mvod_ds_camera,
	.ground_truth = kitti_raw_ground_truth,
	.close = mvod_ds_close,
};
