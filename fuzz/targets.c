/*
 * libFuzzer targets for every parser of outside input. meson builds this file once per target
 * with -DFUZZ_<NAME> (fuzz/meson.build); a new target is a case here and its name there.
 * Besides not crashing (AddressSanitizer watches every access), each parser must keep its
 * promise: on failure a one-line reason; on success a result that is usable.
 */
#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <lcm/eventlog.h>

#include "capture/dataset.h"
#include "capture/euroc_sensor.h"
#include "capture/image_header.h"
#include "capture/oxts.h"
#include "capture/png_grey.h"
#include "capture/uri.h"
#include "mvod/board.h"
#include "mvod/calib.h"
#include "mvod/config.h"
#include "mvod/speed.h"
#include "mvod/traj.h"
#include "ipc/log_check.h"
#include "ipc/lcm_log.h"
#include "mvod/capture.h"
#include "util/lines.h"
#include "util/output.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Each target uses some of the helpers below. */
#define HELPER static __attribute__((unused))

/* The input as the NUL-terminated string the parsers take (libFuzzer's data has no NUL). */
HELPER char *as_string(const uint8_t *data, size_t size)
{
	char *s = malloc(size + 1);
	assert(s);
	memcpy(s, data, size);
	s[size] = '\0';
	return s;
}

/* The input as a file, for the parsers that read one: a memory file, reused, by its path. */
HELPER const char *as_file(const uint8_t *data, size_t size)
{
	static int fd = -1;
	static char path[64];
	if (fd < 0) {
		fd = memfd_create("mvod-fuzz", 0);
		assert(fd >= 0);
		snprintf(path, sizeof(path), "/proc/self/fd/%d", fd);
	}
	int ok = ftruncate(fd, 0) == 0 && pwrite(fd, data, size, 0) == (ssize_t)size;
	assert(ok);
	return path;
}

/* A failure says why, in one line. */
static void check_reason(int ret, const char *err)
{
	if (ret)
		assert(ret < 0 && err[0] && !strchr(err, '\n'));
}

/* Parsed intrinsics are finite, with positive focal lengths and a known distortion count. */
HELPER void check_camera(int ret, const struct mvod_camera *c)
{
	if (!ret)
		assert(c->fx > 0 && c->fy > 0 && isfinite(c->fx) && isfinite(c->fy) &&
		       isfinite(c->cx) && isfinite(c->cy) && c->n_dist >= 0 &&
		       c->n_dist <= (int)(sizeof(c->dist) / sizeof(c->dist[0])));
}

#if defined(FUZZ_URI)
/* Every value goes through both value parsers the backends use; no key is refused. */
static int take_any(void *ctx, const char *key, const char *value, char *err, size_t errlen)
{
	long i;
	double f;
	(void)ctx;
	check_reason(mvod_uri_int(key, value, -1000, 1000, &i, err, errlen), err);
	check_reason(mvod_uri_positive(key, value, 1e6, &f, err, errlen), err);
	return 0;
}
#endif

#if defined(FUZZ_OUTPUT_PATH)
/*
 * A private folder holding a file f, a folder d and a FIFO p, made once and removed at exit.
 * The policy only looks (stat, lstat, readlink, access): nothing is ever written through the
 * fuzzed links, wherever they point.
 */
static char sandbox[64];

static void remove_sandbox(void)
{
	static const char *const names[] = {"l", "f", "p", "d"};
	char path[128];
	for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) {
		snprintf(path, sizeof(path), "%s/%s", sandbox, names[i]);
		remove(path);
	}
	rmdir(sandbox);
}

static const char *make_sandbox(void)
{
	if (sandbox[0])
		return sandbox;
	char path[128];
	snprintf(sandbox, sizeof(sandbox), "/tmp/mvod-fuzz-output-XXXXXX");
	assert(mkdtemp(sandbox));
	snprintf(path, sizeof(path), "%s/f", sandbox);
	FILE *f = fopen(path, "w");
	assert(f && fclose(f) == 0);
	snprintf(path, sizeof(path), "%s/d", sandbox);
	assert(mkdir(path, 0700) == 0);
	snprintf(path, sizeof(path), "%s/p", sandbox);
	assert(mkfifo(path, 0600) == 0);
	atexit(remove_sandbox);
	return sandbox;
}

/* What the policy said is there is there: the kind, and a replaced file named by itself. */
static void check_target(enum mvod_output_kind kind, const char *target)
{
	struct stat st, lst;
	if (kind == MVOD_OUTPUT_NEW)
		return;
	assert(stat(target, &st) == 0);
	assert(kind != MVOD_OUTPUT_REGULAR || (S_ISREG(st.st_mode) && lstat(target, &lst) == 0 &&
					       !S_ISLNK(lst.st_mode)));
	assert(kind != MVOD_OUTPUT_DEVICE || S_ISCHR(st.st_mode));
	assert(kind != MVOD_OUTPUT_FIFO || S_ISFIFO(st.st_mode));
}
#endif

#if defined(FUZZ_LINES)
/* What the line reader handed out: each line text, shorter than its buffer, numbered in turn. */
static int see_line(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	size_t *last = ctx, n = strlen(line);
	(void)err;
	(void)errlen;
	assert(lineno > *last && n < MVOD_LINE_MAX && !strchr(line, '\n'));
	for (size_t i = 0; i < n; i++)
		assert((unsigned char)line[i] >= 0x20 || (line[i] >= '\t' && line[i] <= '\r'));
	*last = lineno;
	return 0;
}
#endif

#if defined(FUZZ_TIMES) || defined(FUZZ_EUROC_INDEX) || defined(FUZZ_TUM_INDEX) || \
	defined(FUZZ_TUM_MONO_INDEX) || defined(FUZZ_KITTI_INDEX) || defined(FUZZ_GT_POSES)
/*
 * One folder per dataset layout, made once, each with three 8x8 frames (P5 bytes: OpenCV and
 * the header reader go by content, not by name) and its fixed files; the fuzzed index or
 * ground truth is written into it per input. Removed at exit.
 */
static char datasets[64];

static void remove_datasets(void)
{
	char cmd[128];
	snprintf(cmd, sizeof(cmd), "rm -rf '%s'", datasets);
	assert(system(cmd) == 0);
}

static void put(const char *rel, const void *bytes, size_t len)
{
	char path[256];
	snprintf(path, sizeof(path), "%s/%s", datasets, rel);
	for (char *s = strchr(path + strlen(datasets) + 1, '/'); s; s = strchr(s + 1, '/')) {
		*s = '\0';
		mkdir(path, 0700);
		*s = '/';
	}
	FILE *f = fopen(path, "wb");
	assert(f && fwrite(bytes, 1, len, f) == len && fclose(f) == 0);
}

static void make_datasets(void)
{
	static const char frame[] = "P5\n8 8\n255\n"
				    "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";
	static const char *const frames[] = {
		"images/0.pgm", "images/1.pgm", "images/2.pgm", "euroc/mav0/cam0/data/1.png",
		"euroc/mav0/cam0/data/2.png", "euroc/mav0/cam0/data/3.png", "tum/rgb/1.png",
		"tum/rgb/2.png", "tum/rgb/3.png", "mono/images/00000.png", "mono/images/00001.png",
		"mono/images/00002.png", "kitti/image_0/000000.png", "kitti/image_0/000001.png",
		"kitti/image_0/000002.png"};
	snprintf(datasets, sizeof(datasets), "/tmp/mvod-fuzz-datasets-XXXXXX");
	assert(mkdtemp(datasets));
	atexit(remove_datasets);
	for (size_t i = 0; i < sizeof(frames) / sizeof(frames[0]); i++)
		put(frames[i], frame, sizeof(frame) - 1);
	static const char sensor[] = "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1, "
				     "0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\nresolution: [8, 8]\n"
				     "camera_model: pinhole\nintrinsics: [10, 10, 3.5, 3.5]\n"
				     "distortion_model: radial-tangential\n"
				     "distortion_coefficients: [0, 0, 0, 0]\n";
	put("euroc/mav0/cam0/sensor.yaml", sensor, sizeof(sensor) - 1);
	static const char *const texts[][2] = {
		{"euroc/mav0/cam0/data.csv", "1000,1.png\n2000,2.png\n3000,3.png\n"},
		{"tum/rgb.txt", "1.0 rgb/1.png\n2.0 rgb/2.png\n3.0 rgb/3.png\n"},
		{"mono/camera.txt", "Pinhole 10 10 3.5 3.5 0\n8 8\ncrop\n8 8\n"},
		{"kitti/calib.txt", "P0: 10 0 3.5 0 0 10 3.5 0 0 0 1 0\n"}};
	for (size_t i = 0; i < sizeof(texts) / sizeof(texts[0]); i++)
		put(texts[i][0], texts[i][1], strlen(texts[i][1]));
}

/*
 * The dataset in folder (scheme:DATASETS/folder) with rel (its index or ground truth) holding
 * the input: opened, its frames' times increasing, the ground truth it carries (gt) poses that
 * are poses. Every noted input is forgotten after, so the list does not grow with the runs.
 */
static int open_dataset(const char *scheme, const char *folder, const char *rel,
			const uint8_t *data, size_t size, bool gt, char *err, size_t errlen)
{
	if (!datasets[0])
		make_datasets();
	put(rel, data, size);
	char full[128];
	snprintf(full, sizeof(full), "%s:%s/%s", scheme, datasets, folder);
	struct mvod_source *src = NULL;
	int ret = mvod_source_open(full, &src, err, errlen);
	struct mvod_traj t = {0};
	if (!ret && gt) {
		char from[256];
		ret = mvod_source_ground_truth(src, &t, from, sizeof(from), err, errlen);
		for (int i = 0; !ret && i < t.n; i++)
			assert(fabs(mvod_mat3_det(t.pose[i].R) - 1) < 1e-6 &&
			       hypot(hypot(t.pose[i].t[0], t.pose[i].t[1]), t.pose[i].t[2]) <=
				       2 * MVOD_POSE_MAX_M + 1);
		mvod_traj_free(&t);
		ret = ret == -ENOENT ? 0 : ret;
	}
	struct mvod_frame f;
	for (int64_t last = INT64_MIN; !ret && mvod_source_read(src, &f) != -ENODATA;) {
		assert(f.utime > last);
		last = f.utime;
	}
	if (src)
		mvod_source_close(src);
	mvod_inputs_forget();
	return ret;
}
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	char err[512] = "";
	int ret;
#if defined(FUZZ_CALIB_JSON) || defined(FUZZ_CALIB_PAIR) || defined(FUZZ_CALIB_FILESTORAGE)
	struct mvod_camera cam;
	char *s = as_string(data, size);
#if defined(FUZZ_CALIB_JSON)
	ret = mvod_calib_parse_json(s, &cam, err, sizeof(err));
#elif defined(FUZZ_CALIB_PAIR)
	ret = mvod_calib_parse_json_pair(s, &cam, err, sizeof(err));
#else
	ret = mvod_calib_parse_filestorage(s, &cam, NULL, err, sizeof(err));
#endif
	free(s);
	check_camera(ret, &cam);
#elif defined(FUZZ_CALIB_KITTI) || defined(FUZZ_CALIB_LOAD)
	struct mvod_camera cam;
#if defined(FUZZ_CALIB_KITTI)
	ret = mvod_calib_load_kitti(as_file(data, size), &cam, err, sizeof(err));
#else
	ret = mvod_calib_load(as_file(data, size), &cam, err, sizeof(err));
#endif
	check_camera(ret, &cam);
#elif defined(FUZZ_CALIB_DSO)
	/* DSO's camera.txt: a camera, its FOV lens's w finite. */
	struct mvod_camera cam;
	char *s = as_string(data, size);
	ret = mvod_calib_parse_dso(s, "camera.txt", &cam, err, sizeof(err));
	free(s);
	check_camera(ret, &cam);
#elif defined(FUZZ_KITTI_RAW)
	/*
	 * KITTI raw's line formats: the input as an OXTS packet (a pose: finite, a rotation) and
	 * each of its lines as a calendar time (within int64 nanoseconds, not before 1970).
	 */
	double packet[6];
	ret = mvod_oxts_read(as_file(data, size), packet, err, sizeof(err));
	if (!ret) {
		struct mvod_pose p;
		mvod_oxts_pose(packet, mvod_oxts_scale(packet[0]), &p);
		assert(fabs(mvod_mat3_det(p.R) - 1) < 1e-9 && isfinite(p.t[0] + p.t[1] + p.t[2]));
	}
	char *s = as_string(data, size);
	for (char *line = strtok(s, "\n"); line; line = strtok(NULL, "\n")) {
		const char *end;
		int64_t ns;
		if (mvod_ds_parse_calendar(line, &end, &ns) == 0)
			assert(ns >= 0 && end > line);
	}
	free(s);
#elif defined(FUZZ_EUROC_SENSOR)
	/* A EuRoC sensor.yaml: a camera, and T_BS a rotation (det 1) with a finite translation. */
	struct mvod_camera cam;
	struct mvod_pose bs;
	ret = mvod_euroc_sensor_load(as_file(data, size), &cam, &bs, err, sizeof(err));
	check_camera(ret, &cam);
	if (!ret)
		assert(fabs(mvod_mat3_det(bs.R) - 1) < 1e-5 && isfinite(bs.t[0] + bs.t[1] + bs.t[2]));
#elif defined(FUZZ_TRAJ)
	struct mvod_traj t;
	ret = mvod_traj_load(as_file(data, size), &t, err, sizeof(err));
	if (!ret) {
		assert(t.n > 0);
		mvod_traj_free(&t);
	}
#elif defined(FUZZ_LINES)
	size_t last = 0;
	ret = mvod_lines_each(as_file(data, size), "fuzz file", see_line, &last, err, sizeof(err));
	mvod_inputs_forget();
#elif defined(FUZZ_IMAGE_HEADER)
	/* A size of 1 or more, or none (-EINVAL, no reason: the caller names the file). */
	int w = 0, h = 0;
	int hret = mvod_image_header_size(data, size, &w, &h);
	assert(hret == 0 ? w >= 1 && h >= 1 : hret == -EINVAL);
	ret = 0;
#elif defined(FUZZ_TIMES)
	ret = open_dataset("images", "images", "images/times.txt", data, size, false, err,
			   sizeof(err));
#elif defined(FUZZ_EUROC_INDEX)
	ret = open_dataset("euroc", "euroc", "euroc/mav0/cam0/data.csv", data, size, false, err,
			   sizeof(err));
#elif defined(FUZZ_TUM_INDEX)
	ret = open_dataset("tum", "tum", "tum/rgb.txt", data, size, false, err, sizeof(err));
#elif defined(FUZZ_TUM_MONO_INDEX)
	ret = open_dataset("tum", "mono", "mono/times.txt", data, size, false, err, sizeof(err));
#elif defined(FUZZ_KITTI_INDEX)
	ret = open_dataset("kitti", "kitti", "kitti/times.txt", data, size, false, err,
			   sizeof(err));
#elif defined(FUZZ_GT_POSES)
	/* The first byte picks the layout: EuRoC's body poses or TUM's camera poses. */
	bool euroc = size > 0 && data[0] & 1;
	ret = open_dataset(euroc ? "euroc" : "tum", euroc ? "euroc" : "tum",
			   euroc ? "euroc/mav0/state_groundtruth_estimate0/data.csv"
				 : "tum/groundtruth.txt",
			   data + (size > 0), size - (size > 0), true, err, sizeof(err));
#elif defined(FUZZ_BOARD)
	struct mvod_board b;
	char *s = as_string(data, size);
	ret = mvod_board_parse(s, &b, err, sizeof(err));
	free(s);
	if (!ret)
		assert(b.cols > 0 && b.rows > 0);
#elif defined(FUZZ_URI)
	char path[256];
	char *s = as_string(data, size);
	ret = mvod_uri_parse(s, path, sizeof(path), take_any, NULL, err, sizeof(err));
	free(s);
	if (!ret)
		assert(strlen(path) < sizeof(path));
#elif defined(FUZZ_OUTPUT_PATH)
	/*
	 * Line 1: the text of a symlink made at SANDBOX/l; line 2: the output's name in SANDBOX.
	 * Line 1 is also read as an --lcm-url: a file:// log's path is what lies before '?'.
	 */
	char *s = as_string(data, size), *nl = strchr(s, '\n');
	const char *name = nl ? nl + 1 : "l";
	if (nl)
		*nl = '\0';
	const char *dir = make_sandbox();
	char link[128], out[4200], target[4096], upath[256];
	snprintf(link, sizeof(link), "%s/l", dir);
	remove(link);
	/* A text the kernel refuses makes no link: that is a case too. */
	if (s[0] && symlink(s, link) != 0)
		assert(errno != EEXIST);
	snprintf(out, sizeof(out), "%s/%s", dir, name);
	enum mvod_output_kind kind;
	ret = mvod_output_check("--out", out, target, sizeof(target), &kind, err, sizeof(err));
	if (!ret)
		check_target(kind, target);
	char mode;
	int uret = mvod_lcm_file_url(s, upath, sizeof(upath), &mode);
	assert(uret == 0 || uret == -ENOENT || uret == -EINVAL || uret == -ENAMETOOLONG);
	assert(uret || strchr("rwa?", mode));
	assert(uret || (upath[0] && !strchr(upath, '?') && strncmp(s + 7, upath, strlen(upath)) == 0));
	free(s);
#elif defined(FUZZ_CONFIG)
	/* What parses prints back as a file that parses to the same settings (prints the same). */
	struct mvod_config c;
	ret = mvod_config_parse_buffer("fuzz.conf", (const char *)data, size, &c, err, sizeof(err));
	if (!ret) {
		char *text = NULL, *again = NULL;
		size_t len = 0, len2 = 0;
		FILE *out = open_memstream(&text, &len);
		assert(out);
		char perr[256];
		int pret = mvod_config_print(&c, out, perr, sizeof(perr));
		fclose(out);
		if (pret == 0) {
			struct mvod_config back;
			char berr[512];
			int bret = mvod_config_parse_buffer("printed", text, len, &back, berr, sizeof(berr));
			assert(bret == 0);
			out = open_memstream(&again, &len2);
			assert(out && mvod_config_print(&back, out, perr, sizeof(perr)) == 0);
			fclose(out);
			assert(len2 == len && memcmp(again, text, len) == 0);
			free(again);
			mvod_config_fini(&back);
		}
		free(text);
		mvod_config_fini(&c);
	}
#elif defined(FUZZ_LCMLOG)
	/*
	 * mvod view's check of an LCM log: a place within the file, and a promise kept: a log
	 * it passes (whole, or cut short at its end) LCM's own reader reads to exactly the
	 * events counted, without crashing, which is what the viewer relies on.
	 */
	const char *path = as_file(data, size);
	struct mvod_lcmlog_check c;
	int fd = open(path, O_RDONLY | O_CLOEXEC);
	assert(fd >= 0);
	ret = mvod_lcmlog_check(fd, &c);
	close(fd);
	if (ret)
		snprintf(err, sizeof(err), "%s", strerror(-ret));
	assert(ret || (c.bad_offset >= -1 && c.bad_offset < (int64_t)size && c.events >= 0));
	if (!ret && (c.bad_offset < 0 || c.cut)) {
		lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
		assert(log);
		int64_t n = 0;
		for (lcm_eventlog_event_t *e; (e = lcm_eventlog_read_next_event(log)); n++)
			lcm_eventlog_free_event(e);
		lcm_eventlog_destroy(log);
		assert(n == c.events);
	}
	/* The same file as --speed-url: refused with a reason, or read to its end; no crash. */
	char url[4200], verr[512];
	snprintf(url, sizeof(url), "file://%s?mode=r", path);
	struct mvod_speed *sp = NULL;
	int sret = mvod_speed_create(url, MVOD_DEFAULT_SPEED_CHANNEL, &sp, err, sizeof(err));
	assert(!sret == !mvod_lcmlog_vet(path, &c, verr, sizeof(verr)));
	assert(!sret || err[0]);
	double metres;
	/* 2001-09-09 in microseconds: a frame time, far past any sample such logs hold. */
	if (sp)
		assert(mvod_speed_odometer(sp, 1000000000000000, &metres) <= 0);
	mvod_speed_destroy(sp);
#elif defined(FUZZ_PNG_GREY)
	/* An 8-bit grey PNG: decoded into a buffer of the size it declares, or refused as such. */
	static struct mvod_png *png; /* one decoder for every input, as for a sequence's frames */
	int w, h;
	ret = 0;
	if (!png)
		assert(!mvod_png_create(&png));
	/* Up to 4096 x 4096: larger sizes only test malloc. */
	if (!mvod_png_grey_size(data, size, &w, &h) && (size_t)w * (size_t)h <= (1u << 24)) {
		uint8_t *img = malloc((size_t)w * (size_t)h);
		assert(img);
		int r = mvod_png_grey_decode(png, data, size, img, (size_t)w);
		assert(r == 0 || r == -EINVAL || r == -ENOTSUP || r == -ENOMEM);
		free(img);
	}
#else
#error "fuzz/targets.c: build with -DFUZZ_<NAME> of a target in fuzz/meson.build"
#endif
	check_reason(ret, err);
	return 0;
}
