/*
 * What mvod publishes, frame by frame, on sequences whose behaviour is known: every pose on
 * MVOD_POSE is the pose of its trajectory line (same frame, time, position and rotation); the
 * state, frame_status and scale_source of each pose follow the VO's rules; and every change
 * of state goes out in a status with the very frame that made it (not at the next periodic
 * status). Nothing here depends on how fast the machine is: each assertion is about which
 * frame carries what.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/geom.h"
#include "mvod_pose_t.h"

#define MAX_POSES 64

/* The poses and statuses of one run, and its trajectory. */
struct run {
	mvod_pose_t pose[MAX_POSES];
	mvod_status_t status[4 * MAX_POSES];
	int poses, statuses;
	struct mvod_traj traj;
};

/* mvod --scale auto --mode mode --frontend frontend on source, trajectory and LCM log into dir. */
static void run_with(const char *dir, const char *source, const char *mode, const char *frontend,
		     struct run *r)
{
	char calib[300], traj[300], log[300], url[320];
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(traj, sizeof(traj), "%s/est.tum", dir);
	snprintf(log, sizeof(log), "%s/mvod.lcmlog", dir);
	snprintf(url, sizeof(url), "file://%s?mode=w", log);
	char *argv[] = {(char *)harness_bin("MVOD"), "-q", "--source", (char *)source, "--calib",
			calib, "--trajectory", traj, "--lcm-url", url, "--mode", (char *)mode,
			"--frontend", (char *)frontend,
			/* map mode: bundle adjustment lands on the same frames whatever the load */
			"--ba-sync", NULL};
	struct run_result res;
	assert_int_equal(harness_run(argv, &res), 0);
	if (!res.exited || res.status != 0)
		fail_msg("mvod failed (%d): %s", res.status, res.err);
	r->poses = harness_poses(log, r->pose, MAX_POSES);
	r->statuses = harness_statuses(log, r->status, 4 * MAX_POSES);
	assert_true(r->poses <= MAX_POSES && r->statuses <= 4 * MAX_POSES);
	char err[512];
	if (mvod_traj_load(traj, &r->traj, err, sizeof(err)))
		fail_msg("%s", err);
}

/*
 * Pose i is trajectory line i: frame number i, the line's time (printed to the microsecond),
 * its position (printed to 9 significant digits) and its rotation (a quaternion to 9 digits:
 * matrix entries to ~1e-8).
 */
static void poses_match_trajectory(const struct run *r, int frames)
{
	assert_int_equal(r->poses, frames);
	assert_int_equal(r->traj.n, frames);
	for (int i = 0; i < frames; i++) {
		const mvod_pose_t *p = &r->pose[i];
		const struct mvod_pose *l = &r->traj.pose[i];
		assert_int_equal(p->frame, i);
		assert_true(fabs(p->utime / 1e6 - r->traj.t[i]) <= 0.5e-6 + 1e-9);
		for (int k = 0; k < 3; k++)
			if (fabs(p->position[k] - l->t[k]) > 1e-8 * fmax(1, fabs(l->t[k])))
				fail_msg("frame %d: position[%d] %.12g on LCM, %.12g in the file", i,
					 k, p->position[k], l->t[k]);
		double R[9];
		mvod_quat_to_rot(p->orientation, R);
		for (int k = 0; k < 9; k++)
			if (fabs(R[k] - l->R[k]) > 1e-8)
				fail_msg("frame %d: rotation entry %d %.12g on LCM, %.12g in the file",
					 i, k, R[k], l->R[k]);
	}
}

/*
 * Each pose whose state differs from the one before (the first: from STARTING) has a status
 * published with it: the status counting frames up to and including it, in the new state.
 */
static void state_changes_published(const struct run *r)
{
	int prev = MVOD_POSE_T_STATE_STARTING;
	for (int i = 0; i < r->poses; i++) {
		int st = r->pose[i].state;
		if (st == prev)
			continue;
		bool found = false;
		for (int k = 0; k < r->statuses && !found; k++)
			found = r->status[k].frames == i + 1 && r->status[k].state == st;
		if (!found)
			fail_msg("frame %d: the state became %d, but no status says so with it", i, st);
		prev = st;
	}
}

/* Frame i's (frame_status, state, scale_source), failing with the frame named. */
static void expect_pose(const struct run *r, int i, int status, int state, int scale)
{
	const mvod_pose_t *p = &r->pose[i];
	if (p->frame_status != status || p->state != state || p->scale_source != scale)
		fail_msg("frame %d: frame_status %d, state %d, scale_source %d; expected %d, %d, %d",
			 i, p->frame_status, p->state, p->scale_source, status, state, scale);
}

/*
 * A free-scale run from its start: the first frame; rotation-only frames (scale none) until
 * parallax allows the first motion, whose length defines the unit; tracking from then on.
 * Returns the first motion frame.
 */
static int expect_start(const struct run *r)
{
	expect_pose(r, 0, MVOD_POSE_T_FRAME_FIRST, MVOD_POSE_T_STATE_INITIALIZING,
		    MVOD_POSE_T_SCALE_NONE);
	int i = 1;
	for (; i < r->poses && r->pose[i].frame_status != MVOD_POSE_T_FRAME_MOTION; i++)
		expect_pose(r, i, MVOD_POSE_T_FRAME_ROTATION, MVOD_POSE_T_STATE_INITIALIZING,
			    MVOD_POSE_T_SCALE_NONE);
	assert_true(i < r->poses);
	expect_pose(r, i, MVOD_POSE_T_FRAME_MOTION, MVOD_POSE_T_STATE_TRACKING,
		    MVOD_POSE_T_SCALE_UNIT);
	return i;
}

/*
 * Frames first .. last - 1 while tracking: motion, scaled by the structure the step shares
 * with the one before or, when too little of it is shared, at the last step's length
 * (constant speed); or rotation only (no translation, scale none). Returns how many motion
 * frames the structure scaled.
 */
static int expect_tracking(const struct run *r, int first, int last)
{
	int structure = 0;
	for (int i = first; i < last; i++) {
		const mvod_pose_t *p = &r->pose[i];
		bool motion = p->frame_status == MVOD_POSE_T_FRAME_MOTION;
		bool by_structure = motion && p->scale_source == MVOD_POSE_T_SCALE_STRUCTURE;
		expect_pose(r, i, motion ? MVOD_POSE_T_FRAME_MOTION : MVOD_POSE_T_FRAME_ROTATION,
			    MVOD_POSE_T_STATE_TRACKING,
			    !motion        ? MVOD_POSE_T_SCALE_NONE
			    : by_structure ? MVOD_POSE_T_SCALE_STRUCTURE
					   : MVOD_POSE_T_SCALE_CONSTANT_SPEED);
		structure += by_structure;
	}
	return structure;
}

/* mvod on a 320x240 video of an mvod-synth path; its poses checked against its trajectory. */
static void run_path_mode(const char *path, int frames, const char *mode, const char *frontend,
			  struct run *r)
{
	char dir[300], src[320];
	snprintf(dir, sizeof(dir), "%s/%s-%s-%s", harness_tmpdir(), path, mode, frontend);
	harness_synth(dir, path, frames, "mkv", "--size", "320x240", NULL);
	snprintf(src, sizeof(src), "file:%s/video.mkv", dir);
	run_with(dir, src, mode, frontend, r);
	poses_match_trajectory(r, frames);
}

static void run_path(const char *path, int frames, struct run *r)
{
	run_path_mode(path, frames, "twoview", "auto", r);
}

static void test_forward(void **state)
{
	(void)state;
	struct run r;
	run_path("forward", 30, &r);
	/*
	 * Structure scales most steps: measured 14 of the 17 motion frames after the first (the
	 * rest fall back to constant speed); fewer than 6 means the structure is not being used.
	 */
	int structure = expect_tracking(&r, expect_start(&r) + 1, 30);
	print_message("%d motion frames scaled by structure\n", structure);
	assert_true(structure >= 6);
	state_changes_published(&r);
	mvod_traj_free(&r.traj);
}

/* Identical frames: rotation only, never tracking, not a step of translation. */
static void test_static(void **state)
{
	(void)state;
	struct run r;
	run_path("static", 10, &r);
	expect_pose(&r, 0, MVOD_POSE_T_FRAME_FIRST, MVOD_POSE_T_STATE_INITIALIZING,
		    MVOD_POSE_T_SCALE_NONE);
	for (int i = 1; i < 10; i++) {
		expect_pose(&r, i, MVOD_POSE_T_FRAME_ROTATION, MVOD_POSE_T_STATE_INITIALIZING,
			    MVOD_POSE_T_SCALE_NONE);
		assert_true(mvod_vec3_norm(r.pose[i].position) == 0);
	}
	state_changes_published(&r);
	mvod_traj_free(&r.traj);
}

/*
 * Twenty frames forward with frames 10 and 11 black, through mode and frontend: each black
 * frame has too few features, tracking is LOST with the first, and the pose holds.
 */
static void run_black(const char *mode, const char *frontend, struct run *r)
{
	char dir[300], images[320], src[340];
	snprintf(dir, sizeof(dir), "%s/black-%s-%s", harness_tmpdir(), mode, frontend);
	harness_synth(dir, "forward", 20, "png", "--size", "320x240", NULL);
	snprintf(images, sizeof(images), "%s/images", dir);
	harness_blacken(images, 10, 320, 240);
	harness_blacken(images, 11, 320, 240);
	snprintf(src, sizeof(src), "images:%s", images);
	run_with(dir, src, mode, frontend, r);
	poses_match_trajectory(r, 20);
	for (int i = 10; i < 12; i++) {
		expect_pose(r, i, MVOD_POSE_T_FRAME_FEW_FEATURES, MVOD_POSE_T_STATE_LOST,
			    MVOD_POSE_T_SCALE_NONE);
		assert_memory_equal(r->pose[i].position, r->pose[9].position,
				    sizeof(r->pose[9].position));
	}
}

/*
 * Two black frames in a forward run (run_black). Frame 12 matches against frame 9, the
 * reference kept through the loss: TRACKING again at once.
 */
static void test_black_frames_lost_and_back(void **state)
{
	(void)state;
	struct run r;
	run_black("twoview", "orb", &r);
	expect_tracking(&r, expect_start(&r) + 1, 10);
	assert_int_equal(r.pose[12].frame_status, MVOD_POSE_T_FRAME_MOTION);
	assert_int_equal(r.pose[12].state, MVOD_POSE_T_STATE_TRACKING);
	expect_tracking(&r, 13, 20);
	state_changes_published(&r);
	mvod_traj_free(&r.traj);
}

/*
 * The default, klt: no track survives a black frame, so frame 12 starts a new reference (few
 * matches) and the pose holds until it has parallax. Measured: 12 few-matches, 13 rotation
 * only, 14 TRACKING; by 14 at the latest (a KLT that re-finds the old reference gets there
 * sooner), and no position invented on the way.
 */
static void test_black_frames_klt_back(void **state)
{
	(void)state;
	struct run r;
	run_black("twoview", "auto", &r);
	expect_tracking(&r, expect_start(&r) + 1, 10);
	int back = 12;
	while (back < 14 && r.pose[back].state != MVOD_POSE_T_STATE_TRACKING) {
		assert_int_equal(r.pose[back].state, MVOD_POSE_T_STATE_LOST);
		assert_memory_equal(r.pose[back].position, r.pose[9].position,
				    sizeof(r.pose[9].position));
		back++;
	}
	expect_tracking(&r, back, 20);
	state_changes_published(&r);
	mvod_traj_free(&r.traj);
}

/*
 * The synthetic path moves at constant speed, so the map's scale must hold: the mean step of
 * the second half of the tracked frames first + 1 .. last - 1 within 1.5 times that of the
 * first half (the scale drift figure of eval.py over two windows; twoview's chained ratios
 * are what it replaces). Single steps are not bounded: a keyframe's bundle adjustment corrects
 * the pose in one step (measured up to 2.1 times the mean).
 */
static void map_scale_holds(const struct run *r, int first, int last)
{
	int mid = (first + 1 + last) / 2;
	double half[2] = {0, 0};
	for (int i = first + 1; i < last; i++)
		half[i >= mid] += sqrt(pow(r->pose[i].position[0] - r->pose[i - 1].position[0], 2) +
				       pow(r->pose[i].position[1] - r->pose[i - 1].position[1], 2) +
				       pow(r->pose[i].position[2] - r->pose[i - 1].position[2], 2));
	double ratio = (half[1] / (last - mid)) / (half[0] / (mid - first - 1));
	print_message("map mode: second half's mean step / first half's = %.3f\n", ratio);
	assert_true(ratio < 1.5 && ratio > 1 / 1.5);
}

/*
 * Map mode forward: after the start (rotation-only frames while parallax builds, then the
 * step that builds the map and defines the unit), every frame is tracked against the map
 * (TRACKING, scale source MAP) and the scale holds; the map's points and keyframes go out on
 * the status. With KLT the points ride on the tracks (measured: no loss in these 30 frames;
 * with 320x240 at 0.1 m a frame the map thins out and is rebuilt at frame 41 of 60).
 */
static void map_forward(const char *frontend)
{
	struct run r;
	run_path_mode("forward", 30, "map", frontend, &r);
	int first = expect_start(&r);
	for (int i = first + 1; i < 30; i++)
		expect_pose(&r, i, MVOD_POSE_T_FRAME_MOTION, MVOD_POSE_T_STATE_TRACKING,
			    MVOD_POSE_T_SCALE_MAP);
	map_scale_holds(&r, first, 30);
	state_changes_published(&r);
	mvod_traj_free(&r.traj);
}

static void test_map_forward(void **state)
{
	(void)state;
	map_forward("orb");
}

static void test_map_klt_forward(void **state)
{
	(void)state;
	map_forward("klt");
}

/*
 * Map mode on a camera that does not translate (identical frames, or turning about its own
 * centre): no map can be built (no parallax), not a step of translation.
 */
static void map_no_translation(const char *path, int frames, const char *frontend)
{
	struct run r;
	run_path_mode(path, frames, "map", frontend, &r);
	for (int i = 1; i < frames; i++) {
		expect_pose(&r, i, MVOD_POSE_T_FRAME_ROTATION, MVOD_POSE_T_STATE_INITIALIZING,
			    MVOD_POSE_T_SCALE_NONE);
		assert_true(mvod_vec3_norm(r.pose[i].position) == 0);
	}
	mvod_traj_free(&r.traj);
}

static void test_map_static(void **state)
{
	(void)state;
	map_no_translation("static", 10, "orb");
}

static void test_map_klt_static(void **state)
{
	(void)state;
	map_no_translation("static", 10, "klt");
}

static void test_map_klt_rotate(void **state)
{
	(void)state;
	map_no_translation("rotate-in-place", 20, "klt");
}

/*
 * Map mode with KLT through two black frames (run_black: LOST, the pose held at frame 9's);
 * the tracks are gone after them, so the map is rebuilt from new ones, carrying the last
 * speed: TRACKING again (measured at frame 14) well before frame 19.
 */
static void test_map_klt_black(void **state)
{
	(void)state;
	struct run r;
	run_black("map", "klt", &r);
	expect_pose(&r, 19, MVOD_POSE_T_FRAME_MOTION, MVOD_POSE_T_STATE_TRACKING,
		    MVOD_POSE_T_SCALE_MAP);
	state_changes_published(&r);
	mvod_traj_free(&r.traj);
}

/*
 * A map-mode run of mvod-synth's path (60 frames, the default front end) beside its ground
 * truth gt (gt.tum); returns s, the run's units per metre: the first motion frame's unit step
 * over the true distance it covers.
 */
static double map_run(const char *path, struct run *r, struct mvod_traj *gt)
{
	run_path_mode(path, 60, "map", "auto", r);
	char file[400], err[512];
	snprintf(file, sizeof(file), "%s/%s-map-auto/gt.tum", harness_tmpdir(), path);
	if (mvod_traj_load(file, gt, err, sizeof(err)))
		fail_msg("%s", err);
	assert_int_equal(gt->n, 60);
	int first = expect_start(r);
	return mvod_vec3_dist(r->pose[first].position, r->pose[0].position) /
	       mvod_vec3_dist(gt->pose[first].t, gt->pose[0].t);
}

/*
 * mvod-synth's full speed (--speed 1 m/s at 10 fps) is 0.1 m a frame; a standing camera's
 * step is allowed 1 % of it, in metres.
 */
#define FULL_STEP_M 0.1
#define STILL_M (0.01 * FULL_STEP_M)

/*
 * The pose never jumps: each step at most k = 2 times the true step (true steps of held frames
 * accumulate into the next moving one), plus STILL_M, all in the run's units s. Measured worst
 * ratios 1.075 (turn) and 1.059 (stop-go): 2 leaves room for the map's scale to wander; a map
 * re-initialised at unit length would step 5 times (turn) or 3 times (stop-go) the true step.
 * Returns the worst ratio among frames that truly moved.
 */
static double map_no_jump(const struct run *r, const struct mvod_traj *gt, double s)
{
	double worst = 0;
	int moved = 0;
	for (int i = 1; i < r->poses; i++) {
		double step = mvod_vec3_dist(r->pose[i].position, r->pose[i - 1].position);
		if (step == 0)
			continue;
		double truth = mvod_vec3_dist(gt->pose[i].t, gt->pose[moved].t);
		if (step > s * (2 * truth + STILL_M))
			fail_msg("frame %d: step %.4f, true %.4f m x %.3f", i, step, truth, s);
		if (truth > STILL_M)
			worst = fmax(worst, step / (s * truth));
		moved = i;
	}
	return worst;
}

/*
 * Frames first .. 59 after a map loss at frame first: every frame not TRACKING that is not a
 * motion step holds the pose, but those waiting for a new map's parallax (ROTATION), which
 * keep the camera's travel (mapping.c, hold_translation); TRACKING frames are steps against
 * the map (scale source MAP) or the step that rebuilt it (scaled by the old map's points the
 * held frame saw, STRUCTURE, else CONSTANT_SPEED); the last frame not TRACKING is before back.
 */
static void map_recovers(const struct run *r, int first, int back)
{
	int last = first;
	for (int i = first; i < 60; i++) {
		const mvod_pose_t *p = &r->pose[i];
		if (p->state != MVOD_POSE_T_STATE_TRACKING) {
			last = i;
			if (p->frame_status == MVOD_POSE_T_FRAME_ROTATION)
				/* waiting for a new map: the camera's travel kept (map_no_jump
				 * bounds it), not held at zero */
				assert_true(mvod_vec3_dist(p->position, r->pose[i - 1].position) > 0);
			else if (p->frame_status != MVOD_POSE_T_FRAME_MOTION)
				assert_memory_equal(p->position, r->pose[i - 1].position,
						    sizeof(p->position));
		} else if (p->scale_source != MVOD_POSE_T_SCALE_CONSTANT_SPEED &&
			   p->scale_source != MVOD_POSE_T_SCALE_STRUCTURE) {
			expect_pose(r, i, MVOD_POSE_T_FRAME_MOTION, MVOD_POSE_T_STATE_TRACKING,
				    MVOD_POSE_T_SCALE_MAP);
		}
	}
	print_message("tracking for good from frame %d\n", last + 1);
	if (last + 1 > back)
		fail_msg("tracking resumed for good at frame %d, later than %d", last + 1, back);
}

/* The first frame after frame from whose state is not TRACKING (60 if none). */
static int map_first_loss(const struct run *r, int from)
{
	int i = from;
	while (i < 60 && r->pose[i].state == MVOD_POSE_T_STATE_TRACKING)
		i++;
	return i;
}

/*
 * The largest rotation error of a run against the ground truth, degrees: of each pose (the
 * angle of R_est^T R_gt; both start at the identity, the first camera being the world) and,
 * in *step, of each frame's rotation from the one before.
 */
static double rotation_error(const struct run *r, const struct mvod_traj *gt, double *step)
{
	double worst = 0, R[60][9];
	*step = 0;
	for (int i = 0; i < r->poses && i < 60; i++) {
		double E[9], a[9], b[9], d[9];
		mvod_quat_to_rot(r->pose[i].orientation, R[i]);
		mvod_mat3_mul_at(R[i], gt->pose[i].R, E);
		worst = fmax(worst, mvod_rot_angle(E));
		if (i == 0)
			continue;
		mvod_mat3_mul_at(R[i - 1], R[i], a);
		mvod_mat3_mul_at(gt->pose[i - 1].R, gt->pose[i].R, b);
		mvod_mat3_mul_at(a, b, d);
		*step = fmax(*step, mvod_rot_angle(d) * 180 / M_PI);
	}
	return worst * 180 / M_PI;
}

/*
 * Map mode on the turn (90 deg left over frames 18-42): the map is tracked into the turn, lost
 * at its sharpest (measured: frame 30, the view sweeps past the map's points), rebuilt only
 * once the pair has 3 px of parallax (mapping.c: the 2-frame pairs of the turn, 2.0-2.9 px,
 * build none; without that gate maps built at 29 and 33 were lost at 32 and 44) and tracked to
 * the end from frame 34 (measured 34, allowed up to 42: a loss must end within the turn, not
 * persist after it; keeping the reference of frame 29 until it shared 39 tracks, as a pure
 * rotation may, rebuilt at 45), and the pose never jumps (worst step over the true one
 * measured 1.075, the frames waiting for the new map at the last speed; 1.19 when they
 * were held at zero and the rebuilding step over frames 31-34 made up for them).
 * The rotation is right throughout: each pose within 1 deg of the truth and each frame's turn
 * within 0.5 deg of the true one (measured 0.24 and 0.11 deg; two-view mode on the same clip
 * 0.04 deg a frame). The steps held while the map waits take their rotation from an
 * essential matrix against the kept reference: one from 38 inliers (frame 35 against 29,
 * before vo.c's keep_overlap) was 24 deg off, and every later pose kept it.
 */
static void test_map_turn(void **state)
{
	(void)state;
	struct run r;
	struct mvod_traj gt;
	double s = map_run("turn", &r, &gt);
	int loss = map_first_loss(&r, expect_start(&r) + 1);
	print_message("turn: map lost at frame %d\n", loss);
	assert_true(loss > 18 && loss < 60); /* measured 30: in the turn, not before it */
	map_recovers(&r, loss, 42);
	print_message("turn: worst step / true step %.3f\n", map_no_jump(&r, &gt, s));
	double step, rot = rotation_error(&r, &gt, &step);
	print_message("turn: rotation error at most %.3f deg, %.3f deg over a frame\n", rot, step);
	assert_true(rot < 1.0);
	assert_true(step < 0.5);
	state_changes_published(&r);
	mvod_traj_free(&gt);
	mvod_traj_free(&r.traj);
}

/*
 * Map mode on stop-go: standing still over frames 24-29 (40-50 % of 60) invents no translation
 * (each standing frame's step below STILL_M, 1 % of a full-speed step, in the run's units:
 * measured 2.6e-5 m, 0.03 %, the map's points re-observed from one place); the map is lost
 * once after pulling away (measured frame 42), tracking against a rebuilt map resumes for
 * good by frame 46 (measured 43: the loss is one frame), and the pose never jumps.
 */
static void test_map_stop_go(void **state)
{
	(void)state;
	struct run r;
	struct mvod_traj gt;
	double s = map_run("stop-go", &r, &gt);
	double still = 0;
	for (int i = 25; i < 30; i++) {
		/* the path stands */
		assert_true(mvod_vec3_dist(gt.pose[i].t, gt.pose[i - 1].t) < 1e-9);
		expect_pose(&r, i, MVOD_POSE_T_FRAME_MOTION, MVOD_POSE_T_STATE_TRACKING,
			    MVOD_POSE_T_SCALE_MAP);
		still = fmax(still, mvod_vec3_dist(r.pose[i].position, r.pose[i - 1].position) / s);
	}
	print_message("stop-go: largest standing step %.6f m (of the run's scale)\n", still);
	assert_true(still < STILL_M);
	int loss = map_first_loss(&r, expect_start(&r) + 1);
	print_message("stop-go: map lost at frame %d\n", loss);
	assert_true(loss >= 30 && loss < 60); /* not while standing: measured 42 */
	map_recovers(&r, loss, 46);
	print_message("stop-go: worst step / true step %.3f\n", map_no_jump(&r, &gt, s));
	state_changes_published(&r);
	mvod_traj_free(&gt);
	mvod_traj_free(&r.traj);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_forward),
		cmocka_unit_test(test_static),
		cmocka_unit_test(test_black_frames_lost_and_back),
		cmocka_unit_test(test_black_frames_klt_back),
		cmocka_unit_test(test_map_forward),
		cmocka_unit_test(test_map_static),
		cmocka_unit_test(test_map_klt_forward),
		cmocka_unit_test(test_map_klt_static),
		cmocka_unit_test(test_map_klt_rotate),
		cmocka_unit_test(test_map_klt_black),
		cmocka_unit_test(test_map_turn),
		cmocka_unit_test(test_map_stop_go),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
