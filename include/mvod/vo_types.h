/*
 * The VO's public types: tracking states, scale modes and sources, front ends, matchers, the
 * parameters and the per-frame result, with their names and the predicates on them (all
 * defined in src/vo/core/params.c). The VO object itself is mvod/vo.h.
 */
#ifndef MVOD_VO_TYPES_H
#define MVOD_VO_TYPES_H

#include <stdbool.h>
#include <stdint.h>

#include "mvod/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The VO's tracking state. Values are mvod.pose_t's STATE_ constants (pinned in src/ipc/ipc.c);
 * the daemon's own states around them are enum mvod_run_state (mvod/pipeline.h).
 */
enum mvod_track_state {
	MVOD_STATE_INITIALIZING = 1, /* no motion estimated yet */
	MVOD_STATE_TRACKING = 2,
	/* The last frame could not be tracked, pose held; map mode: until a lost map is rebuilt. */
	MVOD_STATE_LOST = 3,
};

/* Where the length of a translation step came from. */
enum mvod_scale_source {
	MVOD_SCALE_NONE = 0,           /* no translation this frame */
	MVOD_SCALE_STRUCTURE = 1,      /* ratio of triangulated structure between consecutive pairs */
	MVOD_SCALE_CONSTANT_SPEED = 2, /* structure failed: the previous speed was kept */
	MVOD_SCALE_GROUND_TRUTH = 3,   /* --scale gt */
	MVOD_SCALE_UNIT = 4,           /* first step of a free-scale run: length 1 defines the unit */
	MVOD_SCALE_MAP = 5,            /* map mode: the pose comes from the map, which carries one scale */
	MVOD_SCALE_HEIGHT = 6,         /* metres from the camera's known height above the ground */
	MVOD_SCALE_EXTERNAL = 7,       /* metres from the robot's own speed (mvod.speed_t) */
};

enum mvod_scale_mode {
	MVOD_SCALE_MODE_AUTO = 0,
	MVOD_SCALE_MODE_GT = 1,
	MVOD_SCALE_MODE_HEIGHT = 2,   /* metres from camera_height_m above the ground plane */
	MVOD_SCALE_MODE_EXTERNAL = 3, /* metres from the robot's odometer (mvod_vo_set_odometer) */
};
/* Whether the output of a scale mode is in metres (GT, HEIGHT, EXTERNAL). */
bool mvod_scale_mode_metric(enum mvod_scale_mode m);

/* How poses are estimated. */
enum mvod_vo_mode {
	MVOD_VO_TWOVIEW = 0, /* frame to frame: essential matrix, step length from shared structure */
	MVOD_VO_MAP = 1,     /* a local map of keyframes and points: PnP per frame, windowed BA */
};
/* The modes' names in enum order, NULL-terminated (the config file's choices). */
extern const char *const mvod_vo_mode_names[];

/* Robust estimator of the essential matrix. */
enum mvod_robust_method {
	MVOD_ROBUST_MAGSAC = 0, /* MAGSAC++ (OpenCV USAC): no hard threshold to tune, fewer wrong models */
	MVOD_ROBUST_RANSAC = 1, /* classic RANSAC with a fixed inlier threshold */
};
/* The estimators' names in enum order, NULL-terminated (the config file's choices). */
extern const char *const mvod_robust_names[];

/*
 * How features reach the two-view estimator: detected and matched by descriptor in every frame
 * (ORB, or SIFT with --detector), or FAST corners tracked frame to frame by pyramidal
 * Lucas-Kanade (src/vo/klt.h), which needs no descriptors and no matching.
 */
enum mvod_frontend {
	MVOD_FRONTEND_ORB = 0, /* the descriptor front end */
	MVOD_FRONTEND_KLT = 1,
	/*
	 * The default: mvod_vo_frontend picks one of the two when the VO is created. KLT won on
	 * every figure of BENCHMARKS.md ("The default front end") where it applies.
	 */
	MVOD_FRONTEND_AUTO = 2,
};
/* The front ends' names in enum order, NULL-terminated (the config file's choices). */
extern const char *const mvod_frontend_names[];

/* Keypoint detector and descriptor. */
enum mvod_detector {
	MVOD_DETECTOR_ORB = 0,  /* binary 256-bit descriptors: fast, the default */
	MVOD_DETECTOR_SIFT = 1, /* 128 floats: slower, more distinctive */
};
/* The detectors' names in enum order, NULL-terminated (the config file's choices). */
extern const char *const mvod_detector_names[];
const char *mvod_detector_name(enum mvod_detector d);

/*
 * How features of consecutive frames are paired. Brute force on ORB is mvod's own Hamming
 * table; on SIFT, OpenCV's L2 BFMatcher. FLANN is OpenCV's FlannBasedMatcher: multi-probe LSH
 * (6 tables, key 12 bits, probe level 1) for ORB, 5 randomised kd-trees for SIFT.
 */
enum mvod_matcher_kind {
	MVOD_MATCHER_BF = 0,     /* brute force, ratio test and cross-check: the default */
	MVOD_MATCHER_BF_CROSS,   /* brute force, mutual nearest neighbours, the best_n closest */
	MVOD_MATCHER_BF_RATIO,   /* brute force, ratio test only */
	MVOD_MATCHER_FLANN,      /* FLANN nearest neighbour, unfiltered */
	MVOD_MATCHER_FLANN_RATIO, /* FLANN with the ratio test */
	MVOD_MATCHER_COUNT,
};
/* The matchers' names in enum order, NULL-terminated. */
extern const char *const mvod_matcher_names[];
const char *mvod_matcher_kind_name(enum mvod_matcher_kind m);
/* Whether the kind applies Lowe's ratio test (and so reads mvod_vo_params.ratio). */
bool mvod_matcher_uses_ratio(enum mvod_matcher_kind m);

/* What happened to a frame (the "mark" on a frame whose pose was held). */
enum mvod_frame_status {
	MVOD_FRAME_MOTION = 0,       /* full motion estimated; the frame became the reference */
	MVOD_FRAME_FIRST = 1,        /* first frame / new reference after a loss */
	MVOD_FRAME_ROTATION = 2,     /* too little parallax for translation: rotation only */
	MVOD_FRAME_FEW_FEATURES = 3, /* black, textureless or blurred frame */
	MVOD_FRAME_FEW_MATCHES = 4,
	MVOD_FRAME_RANSAC_FAILED = 5,
	MVOD_FRAME_FEW_INLIERS = 6,
};
const char *mvod_frame_status_name(enum mvod_frame_status s);
const char *mvod_scale_source_name(enum mvod_scale_source s);

enum mvod_stage {
	MVOD_STAGE_CAPTURE = 0,
	MVOD_STAGE_PREPROCESS,
	MVOD_STAGE_DETECT,
	MVOD_STAGE_MATCH,
	MVOD_STAGE_POSE,
	MVOD_STAGE_COUNT,
};
extern const char *const mvod_stage_names[MVOD_STAGE_COUNT];

struct mvod_vo_params {
	enum mvod_vo_mode mode; /* MAP (mvod_vo_run_mode: when it runs two-view instead) */
	double resize;          /* image scale factor in (0, 1]; intrinsics scaled to match. 1 */
	int blur_ksize;         /* Gaussian blur kernel in pixels (odd), 0 = off. 0 */
	enum mvod_frontend frontend; /* AUTO */
	enum mvod_detector detector; /* ORB; the descriptor front end's */
	int max_features;       /* ORB's or SIFT's feature cap (not klt's: max_tracks). 2000 */
	int max_tracks;         /* track cap of the KLT front end. 500 */
	enum mvod_matcher_kind matcher; /* BF */
	double ratio;           /* Lowe's ratio test threshold (matchers with one); >= 1 = off. 0.8 */
	int best_n;             /* BF_CROSS keeps this many closest mutual matches. 200 */
	enum mvod_robust_method robust; /* MAGSAC */
	double ransac_px;       /* inlier threshold (MAGSAC: its upper bound), pixels. 1.0 */
	double ransac_conf;     /* E-RANSAC confidence. 0.999 */
	int min_matches;        /* fewer matches than this: frame not tracked. 30 */
	int min_inliers;        /* fewer E inliers in front of both cameras: not tracked. 20 */
	double min_parallax_px; /* median rotation-compensated flow below this: rotation only
				   (KLT: below half of it), pixels. 1.0 */
	enum mvod_scale_mode scale_mode;
	double camera_height_m; /* HEIGHT: the camera's height above the ground, metres. 0 */
	/*
	 * Map mode: wait for each bundle adjustment at the frame after its keyframe, so results
	 * do not depend on the machine's speed (tests, benchmarks). false: the frame thread never
	 * waits; a result lands at the first frame after it is ready.
	 */
	bool ba_sync;
};
void mvod_vo_params_default(struct mvod_vo_params *p);

/*
 * The flag of the first option that asks for the descriptor front end (detector, matcher,
 * ratio, best: what klt has no counterpart of) whose value in p is not its default, or NULL
 * when all are defaults. Not --features, the ORB and SIFT detectors' count, which picks no
 * front end (klt's budget is --tracks). Compared by value, not by whether it was given, since
 * a file written by --print-config gives every key.
 */
const char *mvod_vo_descriptor_option(const struct mvod_vo_params *p);
/* Those options' flags, NULL-terminated. */
extern const char *const mvod_vo_descriptor_flags[];
/*
 * The front end p runs: p->frontend, or for AUTO, orb when mvod_vo_descriptor_option names an
 * option (the user asked for descriptors), klt otherwise. mvod_vo_create resolves it once;
 * the run loop logs it.
 */
enum mvod_frontend mvod_vo_frontend(const struct mvod_vo_params *p);
/*
 * The one name of the front end p runs, for every log line, summary and table that says it:
 * "klt", or the descriptor front end by its detector, "orb" or "sift" (mvod_frontend_names
 * calls the descriptor front end "orb" whatever it detects: a SIFT run logged "front end: orb").
 */
const char *mvod_vo_frontend_name(const struct mvod_vo_params *p);

struct mvod_vo_result {
	struct mvod_pose pose; /* camera-to-world of this frame */
	enum mvod_track_state state;
	enum mvod_frame_status status;
	enum mvod_scale_source scale_source;
	double step_m;   /* length of the translation applied (scale units), 0 if none */
	int features;    /* keypoints detected */
	int matches;     /* matches after ratio test / cross-check */
	int inliers;     /* E-RANSAC inliers in front of both cameras */
	bool keyframe;   /* map mode: this frame became a keyframe */
	double quality;  /* 0-1: inliers against what tracking needs (0 when not tracked) */
	int map_points;  /* map mode: points in the map (0 in two-view mode) */
	int keyframes;   /* map mode: keyframes in the map */
	/*
	 * Map mode, the frame the map was lost: how many of the map's points fit the frame's pose
	 * (PnP inliers; -1 when too few were found in the frame to try a pose) and how many
	 * tracking needs (min_matches). The frame's status is then the two-view algorithm's,
	 * which takes the frame: the run loop logs this as the reason the state went to LOST.
	 */
	bool map_lost;
	int map_lost_inliers, map_lost_need;
	double scale;    /* metres per unit of the output, 0 when unknown (free scale) */
	double scale_confidence; /* 0-1, 0 when the scale is unknown */
	double ms[MVOD_STAGE_COUNT]; /* stage times for this frame (capture is the caller's) */
};

struct mvod_vo;

/*
 * Whether res is a tracked pose: the state is TRACKING and the frame's motion (or rotation)
 * was estimated. Frames before the first motion (INITIALIZING, even with a rotation estimate)
 * and held frames are not. The summary's "tracked" count and the quality use this.
 */
bool mvod_vo_tracked(const struct mvod_vo_result *res);
/*
 * The pose's quality in [0, 1]: inliers / (MVOD_QUALITY_INLIERS * min_inliers), clamped; 0
 * when the frame is not tracked. Computed by the run loop for every mode. 10 x the default
 * 20 is 200 inliers: measured with the default 2000 features, steady tracking has 260 to 1100
 * (mvod-synth turn at 320x240, 10th to 90th percentile; KITTI 07 at 1226x370: 509 to 726),
 * the frames around a loss of tracking in a fast turn 126 to 254 (quality 0.6 to 1), and
 * min_inliers itself is 0.1.
 */
#define MVOD_QUALITY_INLIERS 10
double mvod_vo_quality(const struct mvod_vo_params *p, const struct mvod_vo_result *res);

/* Smallest processed frame, pixels each way: ORB's 31-pixel patch must fit inside it. */
#define MVOD_VO_MIN_PX 32

#ifdef __cplusplus
}
#endif

#endif
