/*
 * mvod view: what a viewer knows about a running mvod (a bounded path, the latest pose and
 * status, the rate poses arrive at) and the picture of it, in a window or a PNG.
 */
#ifndef MVOD_VIEW_H
#define MVOD_VIEW_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/geom.h"
#include "mvod/ipc.h"
#include "mvod/pipeline.h"
#include "mvod/traj.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The generated LCM types (mvod_pose2_t.h, ...); only the viewer's feeders need them. */
struct _mvod_pose_t;
struct _mvod_status_t;
struct _mvod_pose2_t;
struct _mvod_status2_t;

struct mvod_view {
	struct mvod_path path; /* every position received, decimated to a fixed size */
	int64_t poses, statuses;
	/* The latest pose. */
	struct mvod_pose pose;
	int64_t frame;
	int scale_source, frame_status;
	/*
	 * The newest pose that moved had its step length from ground truth (SCALE_GROUND_TRUTH):
	 * positions are metres. Otherwise they are in a free-scale run's unit, its first step.
	 */
	bool metric;
	int features, matches, inliers;
	double quality; /* 0-1 (v2 poses; 0 from v1) */
	/* A v2 message came (mvod.pose2_t or status2_t): the v1 ones are ignored from then on. */
	bool v2;
	/* The latest status (valid once statuses > 0). */
	struct mvod_status status;
	/* State of the newest message of either kind: status also reports a source that is down. */
	enum mvod_run_state state;
	/*
	 * The newest state other than STOPPING: what the run was doing when it stopped (a run
	 * that never left INITIALIZING ends as one), shown in the big state once mvod stopped.
	 */
	enum mvod_run_state last_state;
	int64_t tracked; /* poses received in state TRACKING: 0 = the run never tracked */
	/* Pose messages that were no pose (mvod_pose_from_quat), not drawn; the first's reason. */
	int64_t refused;
	char refused_why[256];
	/* Receive clock (LCM's recv_utime) of the newest pose, and the pose rate measured on it. */
	int64_t last_pose_us, rate_start_us, rate_start_poses;
	double pose_hz; /* NAN until a second of poses has been seen */
};

/* max_poses: points the path keeps (>= 2); longer runs are decimated. Returns 0 or -ENOMEM. */
int mvod_view_init(struct mvod_view *v, int max_poses);
void mvod_view_fini(struct mvod_view *v);

/*
 * recv_us: when the message arrived (lcm_recv_buf_t.recv_utime), microseconds. The v2 types
 * carry everything; a v1 message (a log of an mvod that published only v1) is taken with the
 * new fields 0, and ignored once any v2 message came, since mvod publishes both.
 */
void mvod_view_add_pose2(struct mvod_view *v, const struct _mvod_pose2_t *msg, int64_t recv_us);
void mvod_view_add_status2(struct mvod_view *v, const struct _mvod_status2_t *msg);
void mvod_view_add_pose(struct mvod_view *v, const struct _mvod_pose_t *msg, int64_t recv_us);
void mvod_view_add_status(struct mvod_view *v, const struct _mvod_status_t *msg);

/*
 * Heading of the latest pose on the ground plane: degrees from the first camera's forward
 * axis (+z) towards its right (+x), in (-180, 180]; NAN before any pose or when the camera
 * looks straight up or down.
 */
double mvod_view_yaw_deg(const struct mvod_view *v);

/*
 * The unit of positions, for labels: "m" when metric, else "units, free scale" (short: "units").
 */
const char *mvod_view_unit(const struct mvod_view *v, bool brief);

/* One line of the text panel: "fps" -> "29.8". */
struct mvod_view_row {
	char label[24];
	char value[48];
};

#define MVOD_VIEW_MAX_ROWS 20
/*
 * The numbers beside the plot (frame, rates, dropped frames, features, quality, map points
 * and keyframes, scale, latency, stage times, RSS, uptime, message counts), as of now_us on the receive clock. Returns the row count.
 */
int mvod_view_rows(const struct mvod_view *v, int64_t now_us, struct mvod_view_row *rows,
		   int max_rows);

/* What the picture says besides the numbers. */
struct mvod_view_labels {
	const char *title;  /* above the plot */
	const char *banner; /* a note under the state, e.g. "end of log"; may be NULL */
};

/* Renders the picture and writes it to path (PNG) through a temporary file and rename(). */
int mvod_view_write_png(const struct mvod_view *v, int64_t now_us,
			const struct mvod_view_labels *labels, const char *path);

/*
 * Whether the display in DISPLAY (or else WAYLAND_DISPLAY) accepts a connection: OpenCV's Qt
 * backend aborts the process when it cannot connect. 0, or -errno with the reason in err.
 */
int mvod_view_display_check(char *err, size_t errlen);

/*
 * A window on the display (OpenCV highgui). open fails with a reason in err when there is no
 * GUI backend. show draws the picture and handles the window's events for a few milliseconds;
 * *quit becomes true when the user pressed q or Esc or closed the window.
 */
int mvod_view_window_open(const char *name, char *err, size_t errlen);
int mvod_view_window_show(const char *name, const struct mvod_view *v, int64_t now_us,
			  const struct mvod_view_labels *labels, int wait_ms, bool *quit);
void mvod_view_window_close(const char *name);

#ifdef __cplusplus
}
#endif

#endif
