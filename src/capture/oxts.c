/*
 * KITTI raw's ground truth and calibration files: the OXTS packets turned into poses as the
 * raw data devkit's convertOxtsToPose (and pykitti's pose_from_oxts_packet) does, and the
 * "KEY: numbers" calibration files that carry the camera and the IMU-to-camera extrinsics.
 */
#include "capture/oxts.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/errbuf.h"
#include "util/numbers.h"
#include "util/linalg.h"
#include "util/lines.h"

/* The devkit's Earth radius for the Mercator projection, metres. */
#define EARTH_RADIUS_M 6378137.0

double mvod_oxts_scale(double lat_deg)
{
	return cos(lat_deg * M_PI / 180);
}

void mvod_oxts_pose(const double p[6], double scale, struct mvod_pose *imu)
{
	imu->t[0] = scale * p[1] * M_PI * EARTH_RADIUS_M / 180;
	imu->t[1] = scale * EARTH_RADIUS_M * log(tan((90 + p[0]) * M_PI / 360));
	imu->t[2] = p[2];
	const double cr = cos(p[3]), sr = sin(p[3]), cp = cos(p[4]), sp = sin(p[4]);
	const double cy = cos(p[5]), sy = sin(p[5]);
	/* Rz(yaw) Ry(pitch) Rx(roll), multiplied out. */
	const double R[9] = {cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
			     sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
			     -sp,     cp * sr,                cp * cr};
	memcpy(imu->R, R, sizeof(R));
}

struct packet {
	const char *path;
	double v[30];
	size_t lines;
};

static int take_packet(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct packet *p = ctx;
	if (p->lines++)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: an OXTS file holds one packet "
				 "(line %zu)", p->path, lineno, lineno - 1);
	int n = mvod_parse_numbers(line, p->v, 30);
	if (n != 30)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: an OXTS packet is 30 numbers "
				 "(lat lon alt roll pitch yaw, then velocities, accelerations, rates, "
				 "accuracies and five counts: dataformat.txt), not \"%.40s\"", p->path,
				 lineno, line);
	return 0;
}

int mvod_oxts_read(const char *path, double packet[6], char *err, size_t errlen)
{
	struct packet p = {.path = path};
	int ret = mvod_lines_each(path, "OXTS packet", take_packet, &p, err, errlen);
	if (!ret && p.lines == 0)
		ret = mvod_errf(err, errlen, -EINVAL, "%s holds no OXTS packet", path);
	/* Latitude within the poles, where the projection is finite. */
	if (!ret && !(fabs(p.v[0]) < 90 && fabs(p.v[1]) <= 180))
		ret = mvod_errf(err, errlen, -EINVAL, "%s line 1: latitude %g, longitude %g degrees "
				"are no place on Earth", path, p.v[0], p.v[1]);
	if (!ret)
		memcpy(packet, p.v, 6 * sizeof(double));
	return ret;
}

/* A key of a KITTI calibration file wanted with n numbers, and the line that gave them. */
struct key {
	const char *name;
	int n;
	double *v;
	size_t line;
};

struct keyfile {
	const char *path;
	struct key *keys;
	int n;
};

/* "KEY: v v v ...": a wanted key's numbers; other keys (calib_time's date) are passed over. */
static int take_key(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct keyfile *f = ctx;
	const char *colon = strchr(line, ':');
	size_t len = colon ? (size_t)(colon - line) : 0;
	for (int i = 0; colon && i < f->n; i++) {
		struct key *k = &f->keys[i];
		if (strlen(k->name) != len || strncmp(line, k->name, len) != 0)
			continue;
		if (k->line)
			return mvod_errf(err, errlen, -EINVAL, "%s line %zu: %s again (first on line "
					 "%zu)", f->path, lineno, k->name, k->line);
		if (mvod_parse_numbers(colon + 1, k->v, k->n) != k->n)
			return mvod_errf(err, errlen, -EINVAL, "%s line %zu: %s must be %d numbers",
					 f->path, lineno, k->name, k->n);
		k->line = lineno;
	}
	return 0;
}

/* dir/name's keys, every one of them there. */
static int read_keys(const char *dir, const char *name, struct key *keys, int n, char *err,
		     size_t errlen)
{
	char path[PATH_MAX];
	int len = snprintf(path, sizeof(path), "%s/%s", dir, name);
	if (len < 0 || (size_t)len >= sizeof(path))
		return mvod_errf(err, errlen, -ENAMETOOLONG, "path too long: %s/%s", dir, name);
	struct keyfile f = {.path = path, .keys = keys, .n = n};
	int ret = mvod_lines_each(path, "KITTI calibration file", take_key, &f, err, errlen);
	for (int i = 0; !ret && i < n; i++)
		if (!keys[i].line)
			ret = mvod_errf(err, errlen, -EINVAL, "%s has no %s: is it KITTI raw's %s?",
					path, keys[i].name, name);
	return ret;
}

/* calib_velo_to_cam.txt's and calib_imu_to_velo.txt's "R:" (row-major) and "T:", X' = R X + T. */
static int read_rigid(const char *dir, const char *name, struct mvod_pose *p, char *err,
		      size_t errlen)
{
	struct key keys[2] = {{"R", 9, p->R, 0}, {"T", 3, p->t, 0}};
	return read_keys(dir, name, keys, 2, err, errlen);
}

int mvod_kitti_raw_calib(const char *dir, struct mvod_camera *cam, struct mvod_pose *cam_imu,
			 char *err, size_t errlen)
{
	double size[2], P[12];
	struct mvod_pose rect = {.t = {0, 0, 0}}, velo_cam, imu_velo, imu_cam;
	struct key keys[3] = {{"S_rect_00", 2, size, 0}, {"R_rect_00", 9, rect.R, 0},
			      {"P_rect_00", 12, P, 0}};
	int ret = read_keys(dir, "calib_cam_to_cam.txt", keys, 3, err, errlen);
	if (!ret)
		ret = read_rigid(dir, "calib_velo_to_cam.txt", &velo_cam, err, errlen);
	if (!ret)
		ret = read_rigid(dir, "calib_imu_to_velo.txt", &imu_velo, err, errlen);
	if (ret)
		return ret;
	/* A pinhole [fx 0 cx 0; 0 fy cy 0; 0 0 1 0] of whole pixels: camera 0's own. */
	if (!(P[0] > 0 && P[5] > 0) || P[1] || P[3] || P[4] || P[7] || P[8] || P[9] || P[10] != 1 ||
	    P[11] || size[0] != floor(size[0]) || size[1] != floor(size[1]) || size[0] < 1 ||
	    size[1] < 1 || size[0] > 65535 || size[1] > 65535)
		return mvod_errf(err, errlen, -EINVAL, "%s/calib_cam_to_cam.txt line %zu or %zu: "
				 "P_rect_00 must be [fx 0 cx 0; 0 fy cy 0; 0 0 1 0], S_rect_00 a size "
				 "in whole pixels", dir, keys[2].line, keys[0].line);
	*cam = (struct mvod_camera){.width = (int)size[0], .height = (int)size[1], .fx = P[0],
				    .cx = P[2], .fy = P[5], .cy = P[6]};
	/* T_cam0_imu = R_rect_00 T_cam_velo T_velo_imu, its rotation made one. */
	mvod_pose_compose(&velo_cam, &imu_velo, &imu_cam);
	mvod_pose_compose(&rect, &imu_cam, cam_imu);
	double R[9], RtR[9], off = 0;
	mvod_mat3_mul_at(cam_imu->R, cam_imu->R, RtR);
	for (int k = 0; k < 9; k++)
		off = fmax(off, fabs(RtR[k] - (k % 4 == 0)));
	/* 1e-4: far above the files' rounding (1e-7), far below any real error. */
	if (!(off < 1e-4) || mvod_nearest_rotation(cam_imu->R, R, NULL) != 0)
		return mvod_errf(err, errlen, -EINVAL, "%s: R_rect_00 (calib_cam_to_cam.txt) and the "
				 "R of calib_velo_to_cam.txt and calib_imu_to_velo.txt multiply to no "
				 "rotation (R^T R off I by %.2g)", dir, off);
	memcpy(cam_imu->R, R, sizeof(R));
	return 0;
}
