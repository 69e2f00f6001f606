#include "mvod/config.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include <ini.h>
#include <lcm/lcm.h>

#include "mvod/vo_types.h"
#include "util/body_frame.h"
#include "util/errbuf.h"
#include "util/input.h"
#include "util/read_file.h"

/* Enum fields are written through an int. */
_Static_assert(sizeof(enum mvod_scale_mode) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_robust_method) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_vo_mode) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_detector) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_frontend) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_matcher_kind) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_traj_format) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_log_level) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_axes) == sizeof(int), "enum size");
_Static_assert(sizeof(enum mvod_clock) == sizeof(int), "enum size");

static const char *const scale_choices[] = {"auto", "gt", "height", "external", NULL};

#define AT(field) offsetof(struct mvod_config, field)
#define KEY(s, k, f, t, field) .section = s, .key = k, .flag = f, .type = t, .offset = AT(field)
/* What --help, --help-all and mvod(1) say of a key: its value's name, a line, and the rest. */
#define DOC(a, s, h) .arg = a, .summary = s, .help = h
#define OPTSTR(s, k, f, field, ...) {KEY(s, k, f, MVOD_CONFIG_STRING, field), .optional = true, \
				     __VA_ARGS__}
#define NUM(s, k, t, field, l, h, ...) {KEY(s, k, k, t, field), .lo = l, .hi = h, __VA_ARGS__}
#define CHOICE(s, k, f, field, c, ...) {KEY(s, k, f, MVOD_CONFIG_ENUM, field), .choices = c, \
					__VA_ARGS__}
#define FLAG(s, k, f, field, v, ...) {KEY(s, k, f, MVOD_CONFIG_BOOL, field), .flag_value = v, \
				      __VA_ARGS__}
/* mvod bench runs without LCM: the [lcm] keys are mvod run's alone. */
#define LCM(k, f, t, field) KEY("lcm", k, f, t, field), .run_only = true

/*
 * The order here is the order of --print-config, of the example mvod.conf, and of --help,
 * --help-all and mvod(1) within each section. The texts are plain: the help module wraps
 * them for a terminal and escapes them for roff; an enum's choices are its value's name.
 */
const struct mvod_config_key mvod_config_keys[] = {
	OPTSTR("source", "uri", "source", run.source,
	       DOC("URI", "where frames come from (required)",
		   "The URI's scheme picks the source, each listed below with its form. Files, "
		   "image folders and datasets give every frame in order; a live camera the "
		   "newest."), .dflt = "none (required)"),
	NUM("source", "max-frames", MVOD_CONFIG_INT64, run.max_frames, 0, 1e12,
	    DOC("N", "stop after N frames; 0: the whole source", NULL)),
	OPTSTR("source", "gt", "gt", run.gt,
	       DOC("FILE", "ground-truth trajectory, TUM or KITTI",
		   "TUM is matched to frames by timestamp, KITTI by index. It adds the accuracy "
		   "summary and the ground truth's path to --plot."),
	       .dflt = "the dataset's own (kitti: ../../poses/NN.txt, kitti-raw: oxts/data/, "
		       "euroc:, tum: groundtruth.txt), as camera poses in the first frame's camera "
		       "frame; else none"),
	{KEY("source", "clock", "clock", MVOD_CONFIG_ENUM, run.clock), .choices = mvod_clock_names,
	 .run_only = true,
	 DOC(NULL, "time base of a camera's utime (v4l2:, libcamera:)",
	     "monotonic: the buffer's CLOCK_MONOTONIC; realtime: the same instant in Unix time, "
	     "to match other sensors' clocks.")},
	OPTSTR("calibration", "file", "calib", run.calib,
	       DOC("FILE", "camera calibration",
		   "mvod JSON (mvod-calibration/1, as mvod calibrate writes it), OpenCV YAML/XML, "
		   "ROS camera_info, JSON [K, dist], KITTI calib.txt or DSO camera.txt (mvod "
		   "calib-convert --help). Not needed for kitti:, kitti-raw: and euroc: sources, "
		   "nor tum: freiburg1/2/3 and monoVO folders. A file whose recorded verdict is "
		   "not good is run with a warning."), .dflt = "the dataset's own; else none"),
	CHOICE("vo", "mode", "mode", run.vo.mode, mvod_vo_mode_names,
	       DOC(NULL, "how poses are estimated: against a map, or frame to frame",
		   "map: a local map of keyframes and points that carries one scale, PnP per frame "
		   "and windowed bundle adjustment on its own thread. twoview: the essential matrix "
		   "frame to frame, each step scaled by the structure it shares with the last; kept "
		   "for comparison, and what --detector sift needs (the map keeps ORB "
		   "descriptors).")),
	CHOICE("vo", "scale", "scale", run.vo.scale_mode, scale_choices,
	       DOC(NULL, "where the step length comes from",
		   "auto: triangulated structure, the first step is the unit; gt: the ground truth "
		   "(benchmarking); height: metres from the ground plane and --camera-height; "
		   "external: metres from the robot's speed, mvod.speed_t (--speed-channel, "
		   "--speed-url; mvod speed-log makes a log of it from a ground truth).")),
	CHOICE("vo", "frontend", "frontend", run.vo.frontend, mvod_frontend_names,
	       DOC(NULL, "how features reach the motion estimate: tracks or descriptors",
		   "klt: FAST corners tracked frame to frame by pyramidal Lucas-Kanade, at most "
		   "--tracks. orb: features detected and matched by descriptor in every frame "
		   "(--detector, --matcher, --ratio, --best apply to it alone, and klt refuses "
		   "them; --features is its count). auto: klt, but orb when one of those four "
		   "options is not its default; --print-config says which runs and why. "
		   "--features never picks a front end.")),
	CHOICE("vo", "detector", "detector", run.vo.detector, mvod_detector_names,
	       DOC(NULL, "the descriptor front end's keypoints: ORB (fast) or SIFT",
		   "SIFT needs --mode twoview.")),
	CHOICE("vo", "matcher", "matcher", run.vo.matcher, mvod_matcher_names,
	       DOC(NULL, "how descriptors of consecutive frames are paired",
		   "bf: brute force, ratio test and cross-check; bf-cross: brute force, mutual "
		   "nearest neighbours, the --best closest; bf-ratio: brute force, ratio test only; "
		   "flann: FLANN nearest neighbour, unfiltered (LSH 6/12/1 for ORB, 5 kd-trees for "
		   "SIFT); flann-ratio: FLANN with the ratio test.")),
	NUM("vo", "features", MVOD_CONFIG_INT, run.vo.max_features, 50, 100000,
	    DOC("N", "ORB's or SIFT's feature count per frame",
		"Picks no front end: with klt running (the default) it is unused and the run "
		"warns; klt's budget is --tracks.")),
	NUM("vo", "tracks", MVOD_CONFIG_INT, run.vo.max_tracks, 50, 100000,
	    DOC("N", "the klt front end's track cap",
		"Where orb runs it is refused, since it would be ignored.")),
	NUM("vo", "ratio", MVOD_CONFIG_DOUBLE, run.vo.ratio, 0.1, 1.0,
	    DOC("R", "Lowe's ratio test threshold; 1 turns it off",
		"For bf, bf-ratio and flann-ratio.")),
	NUM("vo", "best", MVOD_CONFIG_INT, run.vo.best_n, 0, 100000,
	    DOC("N", "matches bf-cross keeps, closest first; 0: all", NULL)),
	CHOICE("vo", "robust", "robust", run.vo.robust, mvod_robust_names,
	       DOC(NULL, "robust estimator of the essential matrix",
		   "magsac: MAGSAC++ (OpenCV's USAC); ransac: classic RANSAC.")),
	NUM("vo", "ransac-px", MVOD_CONFIG_DOUBLE, run.vo.ransac_px, 0.05, 50,
	    DOC("PX", "inlier threshold in pixels (MAGSAC++: its upper bound)", NULL)),
	NUM("vo", "confidence", MVOD_CONFIG_DOUBLE, run.vo.ransac_conf, 0.5, 0.999999,
	    DOC("C", "RANSAC confidence", NULL)),
	NUM("vo", "min-parallax", MVOD_CONFIG_DOUBLE, run.vo.min_parallax_px, 0, 100,
	    DOC("PX", "flow below which a frame is rotation only",
		"The rotation-compensated median flow in pixels; the klt front end uses half of "
		"it.")),
	NUM("vo", "resize", MVOD_CONFIG_DOUBLE, run.vo.resize, 0.05, 1,
	    DOC("F", "scale images by F before tracking", "The intrinsics follow.")),
	{KEY("vo", "blur", "blur", MVOD_CONFIG_INT, run.vo.blur_ksize), .lo = 0, .hi = 99,
	 .odd = true, DOC("K", "Gaussian blur with a KxK kernel; 0: off", NULL)},
	FLAG("vo", "ba-sync", "ba-sync", run.vo.ba_sync, true,
	     DOC(NULL, "map mode, live camera: wait for each bundle adjustment",
		 "At the frame after its keyframe, as files and datasets always do: results "
		 "independent of the machine's speed.")),
	/* 0 = none; above 20 m is no robot's camera: millimetres or feet by mistake. */
	NUM("vo", "camera-height", MVOD_CONFIG_DOUBLE, run.vo.camera_height_m, 0, 20,
	    DOC("M", "the camera's height above the ground in metres, for --scale height",
		"0: none, then the --calib file's mount (mvod mount --help).")),
	{KEY("vo", "speed-channel", "speed-channel", MVOD_CONFIG_STRING, run.speed_channel),
	 .hi = LCM_MAX_CHANNEL_NAME_LENGTH,
	 DOC("NAME", "LCM channel of mvod.speed_t, for --scale external", NULL)},
	OPTSTR("vo", "speed-url", "speed-url", run.speed_url,
	       DOC("URL", "where mvod.speed_t comes from",
		   "An LCM URL, or file://LOG?mode=r to read a log, matched to frames by utime."),
	       .dflt = "the --lcm-url"),
	{LCM("enabled", "no-lcm", MVOD_CONFIG_BOOL, lcm_enabled), .flag_value = false,
	 DOC(NULL, "do not publish over LCM", NULL)},
	{LCM("url", "lcm-url", MVOD_CONFIG_STRING, lcm_url), .optional = true,
	 DOC("URL", "LCM provider",
	     "For example memq:// (in-process) or file:///tmp/mvod.lcmlog?mode=w (a log, written "
	     "whole events at a time)."),
	 .dflt = "$LCM_DEFAULT_URL, then LCM's default"},
	{LCM("pose-channel", "pose-channel", MVOD_CONFIG_STRING, pose_channel),
	 .hi = MVOD_MAX_CHANNEL_LENGTH,
	 DOC("NAME", "LCM channel of mvod.pose_t; mvod.pose2_t goes on NAME2", NULL)},
	{LCM("status-channel", "status-channel", MVOD_CONFIG_STRING, status_channel),
	 .hi = MVOD_MAX_CHANNEL_LENGTH,
	 DOC("NAME", "LCM channel of mvod.status_t; mvod.status2_t goes on NAME2", NULL)},
	{LCM("status-rate", "status-rate", MVOD_CONFIG_DOUBLE, run.status_hz), .lo = 0.1, .hi = 100,
	 DOC("HZ", "status messages per second, besides one on every state change", NULL)},
	OPTSTR("output", "trajectory", "trajectory", run.trajectory,
	       DOC("FILE", "write every pose to FILE",
		   "Each line is written whole, so a killed mvod leaves only complete lines; "
		   "SIGHUP reopens it by name.")),
	{KEY("output", "format", "format", MVOD_CONFIG_ENUM, run.traj_format),
	 .choices = mvod_traj_format_names, .derived = true,
	 DOC(NULL, "trajectory format", NULL),
	 .dflt = "kitti for a --trajectory named *.kitti, else tum"},
	OPTSTR("output", "plot", "plot", run.plot,
	       DOC("FILE.png", "top-down plot of the path, with the ground truth's", NULL)),
	/* Poses in a robot's frame: mvod run's outputs; bench evaluates the camera's. */
	{KEY("output", "frame", "frame", MVOD_CONFIG_ENUM, run.axes), .choices = mvod_axes_names,
	 .run_only = true,
	 DOC(NULL, "axes of the poses on LCM and in --trajectory",
	     "camera: the first camera frame, x right, y down, z forward; ros: the body frame "
	     "at the first frame, x forward, y left, z up. The evaluation against --gt stays in "
	     "the camera frame.")},
	{KEY("output", "camera-to-body", "camera-to-body", MVOD_CONFIG_STRING, run.camera_to_body),
	 .optional = true, .run_only = true, .check = mvod_body_frame_check,
	 DOC("X,Y,Z,QX,QY,QZ,QW", "with --frame ros: the camera's pose in the body frame",
	     "Metres and a unit quaternion."),
	 .dflt = "at the body's origin, level, looking forward: 0,0,0,-0.5,0.5,-0.5,0.5"},
	CHOICE("log", "level", "log-level", log_level, mvod_log_level_names,
	       DOC(NULL, "what is logged to stderr (the journal under systemd)", NULL)),
	{KEY("log", "quiet", "quiet", MVOD_CONFIG_BOOL, quiet), .short_flag = 'q',
	 .flag_value = true, DOC(NULL, "warnings and errors only, and no summary", NULL)},
};
const int mvod_config_nkeys = sizeof(mvod_config_keys) / sizeof(mvod_config_keys[0]);
_Static_assert(sizeof(mvod_config_keys) / sizeof(mvod_config_keys[0]) <= 64,
	       "set and owned are 64-bit masks");

const struct mvod_config_flag mvod_config_flags[MVOD_FLAG_COUNT] = {
	[MVOD_FLAG_CONFIG] = {"config", 0, "FILE", false, "Configuration",
			      "read settings from an INI file; flags override it",
			      "Sections [source] [calibration] [vo] [lcm] [output] [log], one key per "
			      "option (each option's Config: above). An unknown section or key, or a "
			      "bad value, is an error naming the file, line and key. Without --config "
			      "no file is read."},
	[MVOD_FLAG_PRINT_CONFIG] = {"print-config", 0, NULL, false, "Configuration",
				    "print the settings in effect as such a file, then exit",
				    "The file's, then the flags over it; a key that follows others "
				    "(format) is a comment, and frontend = auto says which front end "
				    "runs and why."},
	[MVOD_FLAG_LIST_CAMERAS] = {"list-cameras", 0, NULL, false, "Cameras",
				    "list the cameras attached, then exit",
				    "V4L2 and libcamera cameras, their formats, sizes and rates, each "
				    "with the --source URI that opens it."},
	[MVOD_FLAG_HELP] = {"help", 'h', NULL, true, "General", "a short usage text, then exit",
			    NULL},
	[MVOD_FLAG_HELP_ALL] = {"help-all", 0, NULL, false, "General",
				"every option with its value, default, config key and description, "
				"then exit", NULL},
	[MVOD_FLAG_MAN] = {"man", 0, NULL, false, "General",
			   "the manual page mvod(1) as roff, then exit",
			   "For a build that is not installed: mvod --man | man -l -"},
	[MVOD_FLAG_VERSION] = {"version", 0, NULL, true, "General", "print the version, then exit",
			       NULL},
};

static void *field(struct mvod_config *c, const struct mvod_config_key *k)
{
	return (char *)c + k->offset;
}

static const void *cfield(const struct mvod_config *c, const struct mvod_config_key *k)
{
	return (const char *)c + k->offset;
}

void mvod_config_default(struct mvod_config *c)
{
	*c = (struct mvod_config){
		.pose_channel = MVOD_DEFAULT_POSE_CHANNEL,
		.status_channel = MVOD_DEFAULT_STATUS_CHANNEL,
		.lcm_enabled = true,
		.log_level = MVOD_LOG_INFO,
	};
	mvod_run_opts_default(&c->run);
}

static void drop_string(struct mvod_config *c, int k)
{
	if (c->owned & (1ULL << k))
		free((void *)*(const char **)field(c, &mvod_config_keys[k]));
	c->owned &= ~(1ULL << k);
}

void mvod_config_fini(struct mvod_config *c)
{
	if (!c)
		return;
	for (int k = 0; k < mvod_config_nkeys; k++)
		drop_string(c, k);
	mvod_config_default(c);
}

/* "a", "a or b", "a, b or c". */
static void describe_choices(const char *const *ch, char *err, size_t errlen)
{
	size_t n = 0;
	while (ch[n])
		n++;
	size_t used = 0;
	for (size_t i = 0; i < n && used < errlen; i++) {
		const char *sep = i == 0 ? "" : i + 1 == n ? " or " : ", ";
		int w = snprintf(err + used, errlen - used, "%s%s", sep, ch[i]);
		used += w > 0 ? (size_t)w : 0;
	}
}

static int set_enum(const struct mvod_config_key *k, const char *text, int *out, char *err,
		    size_t errlen)
{
	for (int i = 0; k->choices[i]; i++) {
		if (strcmp(text, k->choices[i]) == 0) {
			*out = i;
			return 0;
		}
	}
	describe_choices(k->choices, err, errlen);
	return -EINVAL;
}

static int set_bool(const char *text, bool *out, char *err, size_t errlen)
{
	static const char *const yes[] = {"true", "yes", "on", "1"};
	static const char *const no[] = {"false", "no", "off", "0"};
	for (int i = 0; i < 4; i++) {
		if (strcmp(text, yes[i]) == 0 || strcmp(text, no[i]) == 0) {
			*out = strcmp(text, yes[i]) == 0;
			return 0;
		}
	}
	return mvod_errf(err, errlen, -EINVAL, "true or false");
}

static int set_number(const struct mvod_config_key *k, const char *text, void *dst, char *err,
		      size_t errlen)
{
	char *end;
	errno = 0;
	bool integer = k->type != MVOD_CONFIG_DOUBLE;
	double v = integer ? (double)strtoll(text, &end, 10) : strtod(text, &end);
	if (errno || end == text || *end || !isfinite(v) || v < k->lo || v > k->hi)
		return mvod_errf(err, errlen, -EINVAL, "%s in [%.15g, %.15g]",
				 integer ? "an integer" : "a number", k->lo, k->hi);
	if (k->odd && v != 0 && fmod(v, 2) == 0)
		return mvod_errf(err, errlen, -EINVAL, "an odd number, or 0");
	if (k->type == MVOD_CONFIG_INT)
		*(int *)dst = (int)v;
	else if (k->type == MVOD_CONFIG_INT64)
		*(int64_t *)dst = (int64_t)v;
	else
		*(double *)dst = v;
	return 0;
}

static int set_value(struct mvod_config *c, int ki, const char *text, char *err, size_t errlen)
{
	const struct mvod_config_key *k = &mvod_config_keys[ki];
	void *dst = field(c, k);
	switch (k->type) {
	case MVOD_CONFIG_STRING:
		if (!*text && !k->optional)
			return mvod_errf(err, errlen, -EINVAL, "a non-empty value");
		if (k->hi > 0 && strlen(text) > k->hi)
			return mvod_errf(err, errlen, -EINVAL, "at most %.0f characters (LCM's limit "
					 "for a channel name, less the 2 of its v2 channel), not %zu", k->hi, strlen(text));
		if (*text && k->check && k->check(text, err, errlen))
			return -EINVAL;
		drop_string(c, ki);
		*(const char **)dst = *text ? text : NULL;
		return 0;
	case MVOD_CONFIG_BOOL:
		if (!text) {
			*(bool *)dst = k->flag_value;
			return 0;
		}
		return set_bool(text, dst, err, errlen);
	case MVOD_CONFIG_ENUM:
		return set_enum(k, text, dst, err, errlen);
	default:
		return set_number(k, text, dst, err, errlen);
	}
}

int mvod_config_set(struct mvod_config *c, int k, const char *text, char *err, size_t errlen)
{
	int ret = set_value(c, k, text, err, errlen);
	if (!ret)
		c->set |= 1ULL << k;
	return ret;
}

/* Parser state: inih hands lines to the handler; the reader counts them. */
struct parse {
	const char *name;
	const char *p, *end; /* what is left of the text */
	int line;            /* of the line last handed to inih */
	int err_line;        /* of the first error the reader or the handler found, 0 if none */
	char *err;
	size_t errlen;
	struct mvod_config *c;
};

static int key_index(const char *section, const char *key, bool *section_known)
{
	*section_known = false;
	for (int k = 0; k < mvod_config_nkeys; k++) {
		if (strcmp(section, mvod_config_keys[k].section) != 0)
			continue;
		*section_known = true;
		if (strcmp(key, mvod_config_keys[k].key) == 0)
			return k;
	}
	return -1;
}

/* "a, b, c": the keys of a section. */
static const char *keys_of(const char *section, char *buf, size_t len)
{
	size_t used = 0;
	buf[0] = '\0';
	for (int k = 0; k < mvod_config_nkeys && used < len; k++) {
		if (strcmp(section, mvod_config_keys[k].section) != 0)
			continue;
		int w = snprintf(buf + used, len - used, "%s%s", used ? ", " : "",
				 mvod_config_keys[k].key);
		used += w > 0 ? (size_t)w : 0;
	}
	return buf;
}

/* Keeps the first error only: "NAME:LINE: what". */
__attribute__((format(printf, 2, 3))) static void parse_error(struct parse *ps, const char *fmt,
							       ...)
{
	if (ps->err_line || !ps->errlen)
		return;
	ps->err_line = ps->line;
	int n = snprintf(ps->err, ps->errlen, "%s:%d: ", ps->name, ps->line);
	if (n < 0 || (size_t)n >= ps->errlen)
		return;
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(ps->err + n, ps->errlen - (size_t)n, fmt, ap);
	va_end(ap);
}

static int on_key(void *user, const char *section, const char *key, const char *value)
{
	struct parse *ps = user;
	char known[256];
	bool section_known;
	int k = key_index(section, key, &section_known);
	if (!*section) {
		parse_error(ps, "%s: every key belongs in a section ([source], [vo], ...)", key);
		return 0;
	}
	if (k < 0) {
		if (section_known)
			parse_error(ps, "[%s] %s: unknown key; [%s] has %s", section, key, section,
				    keys_of(section, known, sizeof(known)));
		else
			parse_error(ps, "[%s] %s: unknown section; the sections are [source] "
					"[calibration] [vo] [lcm] [output] [log]", section, key);
		return 0;
	}
	char *copy = NULL;
	if (mvod_config_keys[k].type == MVOD_CONFIG_STRING && *value && !(copy = strdup(value))) {
		parse_error(ps, "[%s] %s: out of memory", section, key);
		return 0;
	}
	char want[256];
	if (mvod_config_set(ps->c, k, copy ? copy : value, want, sizeof(want))) {
		free(copy);
		parse_error(ps, "[%s] %s = %s: expected %s", section, key, value, want);
		return 0;
	}
	if (copy)
		ps->c->owned |= 1ULL << k;
	return 1;
}

/*
 * inih's reader: one line per call. Leading blanks go, since inih would take an indented line
 * for the continuation of the key before it; a line that does not fit or holds a NUL ends the
 * parse with an error, since inih would silently split or cut it.
 */
static char *next_line(char *str, int num, void *stream)
{
	struct parse *ps = stream;
	if (ps->p >= ps->end || ps->err_line)
		return NULL;
	ps->line++;
	const char *nl = memchr(ps->p, '\n', (size_t)(ps->end - ps->p));
	const char *eol = nl ? nl + 1 : ps->end;
	const char *s = ps->p;
	while (s < eol && (*s == ' ' || *s == '\t'))
		s++;
	size_t n = (size_t)(eol - s);
	ps->p = eol;
	if (memchr(s, '\0', n)) {
		parse_error(ps, "a NUL byte: not a text file");
		return NULL;
	}
	if (n > (size_t)num - 1 || n > MVOD_CONFIG_MAX_LINE + 1) {
		parse_error(ps, "line longer than %d characters", MVOD_CONFIG_MAX_LINE);
		return NULL;
	}
	memcpy(str, s, n);
	str[n] = '\0';
	return str;
}

int mvod_config_parse_buffer(const char *name, const char *text, size_t len,
			     struct mvod_config *out, char *err, size_t errlen)
{
	mvod_config_default(out);
	struct parse ps = {.name = name, .p = text, .end = text + len, .err = err,
			   .errlen = errlen, .c = out};
	int ret = ini_parse_stream(next_line, &ps, on_key, &ps);
	if (ret == 0 && !ps.err_line)
		return 0;
	/* inih reports the first bad line; when that is not one we explained, it is malformed. */
	if (ret > 0 && (!ps.err_line || ret < ps.err_line)) {
		ps.err_line = 0;
		ps.line = ret;
		parse_error(&ps, "not a [section] or key = value line");
	}
	mvod_config_fini(out);
	return -EINVAL;
}

int mvod_config_load(const char *path, struct mvod_config *out, char *err, size_t errlen)
{
	char *text = NULL;
	size_t len = 0;
	mvod_config_default(out);
	int ret = mvod_read_file(path, 1 << 20, "config file", MVOD_INPUT_STREAM, &text, &len, err,
				 errlen);
	if (ret)
		return ret;
	ret = mvod_config_parse_buffer(path, text, len, out, err, errlen);
	free(text);
	return ret;
}

static const size_t field_size[] = {
	[MVOD_CONFIG_STRING] = sizeof(const char *), [MVOD_CONFIG_INT] = sizeof(int),
	[MVOD_CONFIG_INT64] = sizeof(int64_t),       [MVOD_CONFIG_DOUBLE] = sizeof(double),
	[MVOD_CONFIG_BOOL] = sizeof(bool),           [MVOD_CONFIG_ENUM] = sizeof(int),
};

void mvod_config_override(struct mvod_config *dst, struct mvod_config *src)
{
	for (int k = 0; k < mvod_config_nkeys; k++) {
		uint64_t bit = 1ULL << k;
		if (!(src->set & bit))
			continue;
		const struct mvod_config_key *key = &mvod_config_keys[k];
		if (key->type == MVOD_CONFIG_STRING)
			drop_string(dst, k);
		memcpy(field(dst, key), cfield(src, key), field_size[key->type]);
		dst->set |= bit;
		dst->owned |= src->owned & bit;
		src->owned &= ~bit;
	}
}

static int key_of_field(size_t offset)
{
	for (int k = 0; k < mvod_config_nkeys; k++)
		if (mvod_config_keys[k].offset == offset)
			return k;
	return -1;
}

void mvod_config_finish(struct mvod_config *c)
{
	int fk = key_of_field(AT(run.traj_format));
	size_t n = c->run.trajectory ? strlen(c->run.trajectory) : 0;
	if (!(c->set & (1ULL << fk)) && n >= 6 && strcmp(c->run.trajectory + n - 6, ".kitti") == 0)
		c->run.traj_format = MVOD_TRAJ_KITTI;
}

void mvod_config_apply_log(const struct mvod_config *c)
{
	enum mvod_log_level l = c->log_level;
	mvod_log_set_level(c->quiet && l > MVOD_LOG_WARN ? MVOD_LOG_WARN : l);
}

/* The shortest text that reads back as exactly v: 0.8, not 0.80000000000000004. */
static void format_double(double v, char *buf, size_t len)
{
	for (int digits = 15; digits <= 17; digits++) {
		snprintf(buf, len, "%.*g", digits, v);
		if (strtod(buf, NULL) == v)
			return;
	}
}

/* The value of key k as INI text, into buf. */
static void format_value(const struct mvod_config *c, const struct mvod_config_key *k, char *buf,
			 size_t len)
{
	const void *v = cfield(c, k);
	switch (k->type) {
	case MVOD_CONFIG_STRING: {
		const char *s = *(const char *const *)v;
		snprintf(buf, len, "%s", s ? s : "");
		return;
	}
	case MVOD_CONFIG_INT: snprintf(buf, len, "%d", *(const int *)v); return;
	case MVOD_CONFIG_INT64: snprintf(buf, len, "%lld", (long long)*(const int64_t *)v); return;
	case MVOD_CONFIG_DOUBLE: format_double(*(const double *)v, buf, len); return;
	case MVOD_CONFIG_BOOL: snprintf(buf, len, "%s", *(const bool *)v ? "true" : "false"); return;
	case MVOD_CONFIG_ENUM: snprintf(buf, len, "%s", k->choices[*(const int *)v]); return;
	}
}

void mvod_config_value_text(const struct mvod_config *c, int k, char *buf, size_t len)
{
	format_value(c, &mvod_config_keys[k], buf, len);
}

/* Whether inih reads "key = value" back as value. */
static const char *unprintable(const struct mvod_config_key *k, const char *value)
{
	size_t n = strlen(value);
	if (strchr(value, '\n') || strchr(value, '\r'))
		return "a line break";
	if (strstr(value, " ;") || strstr(value, "\t;") || value[0] == ';')
		return "\" ;\", which starts a comment in INI";
	if (n && (value[0] == ' ' || value[0] == '\t' || value[n - 1] == ' ' || value[n - 1] == '\t'))
		return "blanks around it";
	if (strlen(k->key) + 3 + n > MVOD_CONFIG_MAX_LINE)
		return "more characters than an INI line can hold";
	return NULL;
}

static int key_of_flag(const char *flag)
{
	for (int k = 0; k < mvod_config_nkeys; k++)
		if (strcmp(mvod_config_keys[k].flag, flag) == 0)
			return k;
	return -1;
}

/*
 * After frontend = auto, which front end that runs and why, as an INI comment (the key stays
 * auto when the printout is read back, and keeps choosing): "  ; runs klt: none of detector,
 * matcher, ratio, best (orb and sift only) set", or "  ; runs orb: matcher = flann (...) set".
 */
static void frontend_note(const struct mvod_config *c, const struct mvod_config_key *k,
			  char *buf, size_t len)
{
	const struct mvod_vo_params *p = &c->run.vo;
	buf[0] = '\0';
	if (k->offset != AT(run.vo.frontend) || p->frontend != MVOD_FRONTEND_AUTO)
		return;
	const char *opt = mvod_vo_descriptor_option(p);
	int used = snprintf(buf, len, "  ; runs %s: ", mvod_vo_frontend_name(p));
	if (used < 0 || (size_t)used >= len)
		return;
	if (opt) {
		char value[64];
		format_value(c, &mvod_config_keys[key_of_flag(opt)], value, sizeof(value));
		snprintf(buf + used, len - (size_t)used, "%s = %s (orb and sift only) set", opt, value);
		return;
	}
	used += snprintf(buf + used, len - (size_t)used, "none of ");
	for (int i = 0; mvod_vo_descriptor_flags[i] && (size_t)used < len; i++)
		used += snprintf(buf + used, len - (size_t)used, "%s%s", i ? ", " : "",
				 mvod_vo_descriptor_flags[i]);
	if ((size_t)used < len)
		snprintf(buf + used, len - (size_t)used, " (orb and sift only) set");
}

int mvod_config_print(const struct mvod_config *c, FILE *out, char *err, size_t errlen)
{
	const char *section = "";
	fprintf(out, "# mvod configuration (mvod --print-config); see mvod --help\n");
	for (int i = 0; i < mvod_config_nkeys; i++) {
		const struct mvod_config_key *k = &mvod_config_keys[i];
		char value[4096];
		format_value(c, k, value, sizeof(value));
		const char *why = unprintable(k, value);
		if (why)
			return mvod_errf(err, errlen, -EINVAL, "[%s] %s: the value has %s", k->section,
					 k->key, why);
		if (strcmp(section, k->section) != 0)
			fprintf(out, "%s[%s]\n", i ? "\n" : "", k->section);
		section = k->section;
		bool derived = k->derived && !(c->set & (1ULL << i));
		char note[160];
		frontend_note(c, k, note, sizeof(note));
		fprintf(out, "%s%s =%s%s%s%s\n", derived ? "# " : "", k->key, *value ? " " : "", value,
			derived ? "  (not set: follows other keys; uncomment to fix it)" : "", note);
	}
	return ferror(out) ? mvod_errf(err, errlen, -EIO, "write error") : 0;
}
