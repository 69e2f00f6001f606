/* Camera intrinsics and the calibration files that carry them. */
#ifndef MVOD_CALIB_H
#define MVOD_CALIB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MVOD_CALIB_FORMAT "mvod-calibration/1"
#define MVOD_MAX_DIST 14

enum mvod_cam_model {
	MVOD_CAM_PINHOLE_RADTAN = 0, /* OpenCV model: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tx ty]]]] */
	MVOD_CAM_FISHEYE_KB4 = 1,    /* Kannala-Brandt, OpenCV fisheye: k1 k2 k3 k4 */
	MVOD_CAM_FOV = 2,            /* FOV (arctangent) lens of PTAM and DSO: w, radians */
};

struct mvod_camera {
	int width, height;     /* pixels; 0 when the file does not say (KITTI calib.txt) */
	double fx, fy, cx, cy; /* pixels */
	enum mvod_cam_model model;
	int n_dist;                  /* number of valid entries in dist (0 = none) */
	double dist[MVOD_MAX_DIST];  /* OpenCV order for the model */
	/*
	 * The lens focus position (device units) the intrinsics were measured at, when the camera
	 * reported one: a different focus changes the focal length. A flag rather than NaN so that
	 * a zero-initialised camera still means "unknown".
	 */
	bool has_focus;
	double focus;
	/*
	 * How the camera is mounted above the ground ("mount" in mvod JSON, mount_height_m,
	 * mount_pitch_deg and mount_roll_deg in OpenCV and ROS YAML/XML), when known:
	 * --scale height takes its height (metres) when --camera-height is not given, and its
	 * pitch (degrees, positive looking down) and roll (degrees, positive: the ground's normal
	 * leans towards +x) as the ground normal's first estimate.
	 */
	bool has_mount;
	double mount_height_m, mount_pitch_deg, mount_roll_deg;
	/*
	 * mvod calibrate's verdict on these intrinsics when the file records one (mvod JSON's
	 * "verdict": "good", "too few views", "not one camera", ...), else "": mvod run warns
	 * at start on any but good.
	 */
	char verdict[32];
};

/* Largest mount height taken, metres: above any robot or car; the same bound as --camera-height. */
#define MVOD_MOUNT_MAX_HEIGHT_M 20.0
/* Largest |pitch| and |roll|, degrees: beyond it the ground is out of a forward camera's view. */
#define MVOD_MOUNT_MAX_ANGLE_DEG 60.0

/*
 * What a calibration file records besides the intrinsics. A zero-initialised meta records
 * nothing but "rms_px": 0; every other field is written only when set. Pointers are borrowed.
 */
struct mvod_calib_meta {
	double rms_px;     /* reprojection RMS in pixels; negative = unknown */
	char board[128];   /* board spec, or "" */
	char source[256];  /* what it was made from */
	int n_views;                 /* views the calibration used; 0 = not recorded */
	const double *view_rms_px;   /* n_views reprojection RMS values, pixels */
	const double *view_pose;     /* n_views x 6: board-to-camera rvec (rad), tvec (metres) */
	const int64_t *view_frame;   /* n_views source frame indices (from 0), or NULL */
	bool has_std;                /* std_K and std_dist hold standard deviations */
	double std_K[4];             /* fx fy cx cy, pixels */
	double std_dist[MVOD_MAX_DIST]; /* one per distortion coefficient of the camera */
	char verdict[32];            /* mvod calibrate's verdict ("good", ...), or "" */
};

/* "pinhole-radtan" / "fisheye-kb4" / "fov" and back. */
const char *mvod_cam_model_name(enum mvod_cam_model model);
int mvod_cam_model_parse(const char *name, enum mvod_cam_model *out);

/* True when any distortion coefficient is non-zero. */
bool mvod_camera_has_distortion(const struct mvod_camera *cam);

/*
 * Whether cam (width and height set) can be a real camera of that size: fx and fy within 0.05
 * to 20 times the width, the principal point within half the image size around the image, and
 * a lens model that moves every point strictly outward from the principal point up to the
 * image edge (no fold), at most 4 times as far as a pinhole would. -EINVAL with a one-line
 * reason giving the value and the range.
 */
int mvod_camera_check(const struct mvod_camera *cam, char *err, size_t errlen);

/*
 * Where the normalised undistorted point (x, y) (a ray at z = 1) lands, distorted and still
 * normalised, through cam's lens (src/camera/lens.c).
 */
void mvod_camera_distort(const struct mvod_camera *cam, double x, double y, double *xd,
			 double *yd);

/*
 * The FOV lens (Devernay and Faugeras; PTAM's ATAN camera, DSO's FOV): a ray at normalised
 * radius r lands at r_d = atan(2 r tan(w / 2)) / w, w its field of view in radians, in
 * [0, pi); back, r = tan(r_d w) / (2 tan(w / 2)), INFINITY where no ray lands (r_d w >= pi/2).
 */
double mvod_fov_distort_radius(double omega, double r);
double mvod_fov_undistort_radius(double omega, double rd);

/*
 * Undistortion maps into an ideal pinhole K (row-major [fx 0 cx; 0 fy cy; 0 0 1]) of w x h
 * pixels: mapx, mapy[v * w + u] (w * h floats each, the caller's) = where output pixel (u, v)
 * lies in cam's image, pixels, as cv::remap takes them; for the lens OpenCV has no model for.
 */
void mvod_camera_undistort_maps(const struct mvod_camera *cam, const double K[9], int w, int h,
				float *mapx, float *mapy);

/* The camera matrix [fx 0 cx; 0 fy cy; 0 0 1], row-major (skew is not modelled). */
void mvod_camera_K(const struct mvod_camera *cam, double K[9]);

/*
 * Loads a calibration file, choosing the reader by content: mvod JSON (mvod-calibration/1),
 * a JSON [K, dist] pair, KITTI calib.txt (P0), OpenCV FileStorage YAML/XML or ROS camera_info
 * YAML (see below). On failure returns -errno and writes a one-line reason naming the file to err.
 */
int mvod_calib_load(const char *path, struct mvod_camera *cam, char *err, size_t errlen);
/* KITTI odometry calib.txt: intrinsics from P0, no distortion, image size unknown (0). */
int mvod_calib_load_kitti(const char *path, struct mvod_camera *cam, char *err, size_t errlen);
/* DSO's camera.txt (mvod_calib_parse_dso), whatever its content looks like. */
int mvod_calib_load_dso(const char *path, struct mvod_camera *cam, char *err, size_t errlen);
/* mvod JSON from a NUL-terminated buffer (the file reader and the tests share it). */
int mvod_calib_parse_json(const char *text, struct mvod_camera *cam, char *err, size_t errlen);

/*
 * Writes mvod JSON to path through a temporary file in the same directory and rename(), so an
 * existing file is replaced whole or not at all. meta may be NULL.
 */
int mvod_calib_save(const char *path, const struct mvod_camera *cam, const struct mvod_calib_meta *meta);

/* The calibration file formats mvod reads (all) and writes (all but the [K, dist] pair). */
enum mvod_calib_format {
	MVOD_CALIB_FMT_MVOD = 0,   /* mvod JSON, mvod-calibration/1 */
	MVOD_CALIB_FMT_OPENCV = 1, /* OpenCV FileStorage YAML or XML */
	MVOD_CALIB_FMT_ROS = 2,    /* ROS camera_info YAML */
	MVOD_CALIB_FMT_KITTI = 3,  /* KITTI odometry calib.txt */
	MVOD_CALIB_FMT_PAIR = 4,   /* JSON [K, dist] or {"K": K, "dist": dist} (read only) */
	MVOD_CALIB_FMT_DSO = 5,    /* DSO's camera.txt, as TUM monoVO ships it */
};

/* "mvod", "opencv", "ros", "kitti", "pair", "dso" and back; a longer description for messages. */
const char *mvod_calib_format_name(enum mvod_calib_format fmt);
const char *mvod_calib_format_title(enum mvod_calib_format fmt);
int mvod_calib_format_parse(const char *name, enum mvod_calib_format *out);

/* mvod_calib_load, also saying which format the file was in (fmt may be NULL). */
int mvod_calib_load_format(const char *path, struct mvod_camera *cam, enum mvod_calib_format *fmt,
			   char *err, size_t errlen);

/*
 * A JSON [K, dist] pair (as numpy's tolist() or many scripts dump it): K as 3 rows or 9
 * numbers, dist as a list (or a 1xN nested list) of 0, 4, 5, 8, 12 or 14 coefficients; or the
 * object {"K": K, "dist": dist} with an optional "model" ("fisheye-kb4"). No image size: 0.
 */
int mvod_calib_parse_json_pair(const char *text, struct mvod_camera *cam, char *err, size_t errlen);

/*
 * OpenCV FileStorage YAML/XML or ROS camera_info YAML (read with libyaml and libxml2; XML
 * with a DOCTYPE is refused, and only the first YAML document is read): K from
 * camera_matrix (or M1, the first camera of OpenCV's stereo_calib sample), coefficients from
 * distortion_coefficients (or D1). The model is pinhole-radtan unless distortion_model says
 * equidistant, fisheye or fisheye-kb4, or fov (mvod's own value for the FOV lens, 1
 * coefficient); OpenCV's own files cannot say, so 4 coefficients are k1 k2 p1 p2 there.
 * image_width and image_height are optional (0 when absent). fmt (may be NULL) says whether
 * the text was OpenCV's (with its header, or XML) or ROS's. The mount is
 * read from the optional top-level scalars mount_height_m (required with the others),
 * mount_pitch_deg and mount_roll_deg (0 when absent), with mvod JSON's bounds.
 */
int mvod_calib_parse_filestorage(const char *text, struct mvod_camera *cam,
				 enum mvod_calib_format *fmt, char *err, size_t errlen);

/*
 * DSO's camera.txt (JakobEngel/dso's README; TUM monoVO ships one per sequence): line 1 the
 * lens, "FOV fx fy cx cy w" (also "ATAN", or 5 bare numbers: FOV, a pinhole when w is 0),
 * "Pinhole fx fy cx cy 0", "RadTan fx fy cx cy k1 k2 p1 p2" (or 8 bare numbers),
 * "EquiDistant" or "KannalaBrandt fx fy cx cy k1 k2 k3 k4"; relative (cx, cy < 1: fractions
 * of the image, pixel edges at 0, as DSO reads them) or in pixels; line 2 "width height";
 * optional lines 3 and 4, DSO's rectification (crop, full, none or "fx fy cx cy 0") and its
 * output size, checked and not used. Errors name path and the line.
 */
int mvod_calib_parse_dso(const char *text, const char *path, struct mvod_camera *cam, char *err,
			 size_t errlen);

/*
 * The OpenCV or ROS YAML camera file text with its mount set to mount (height_m, pitch_deg,
 * roll_deg) as the scalars mount_height_m, mount_pitch_deg and mount_roll_deg: a value there
 * is replaced in its place, the missing keys are added where the top-level map ends; every
 * other byte is kept. The result is read back and must give the same camera with this mount.
 * XML is refused (-ENOTSUP), as is YAML whose top level is no block map. *out: malloc'd, for
 * free. Returns 0 or -errno with a one-line reason in err.
 */
int mvod_calib_filestorage_set_mount(const char *text, const double mount[3], char **out, char *err,
				     size_t errlen);

/*
 * Writers, each through a temporary file and rename(). OpenCV: YAML, or XML when path ends in
 * ".xml"; a fisheye camera gets "distortion_model: fisheye" (an FOV one "fov") so that mvod
 * reads it back as one.
 * OpenCV and ROS carry the mount as above; KITTI has no place for it.
 * ROS: camera_info YAML (plumb_bob, rational_polynomial or equidistant; needs the image size).
 * KITTI: P0..P3 all [K | 0]; refuses a camera with distortion, since calib.txt cannot carry it.
 * ROS refuses the FOV lens (image_geometry has no model for it).
 * DSO: camera.txt in pixels, "MODEL fx fy cx cy params" (FOV, Pinhole, RadTan or
 * KannalaBrandt), the size, and DSO's "crop" (a distortion-free pinhole: "none") at the same
 * size; needs the image size, refuses radial-tangential coefficients past the 4th and the
 * mount (camera.txt has no place for it; the caller notes that).
 */
int mvod_calib_save_opencv(const char *path, const struct mvod_camera *cam, char *err, size_t errlen);
int mvod_calib_save_ros(const char *path, const struct mvod_camera *cam, char *err, size_t errlen);
int mvod_calib_save_kitti(const char *path, const struct mvod_camera *cam, char *err, size_t errlen);
int mvod_calib_save_dso(const char *path, const struct mvod_camera *cam, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
