/* mvod calib-convert: reads any calibration file mvod understands and writes it in another format. */
#include "cli/cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/calib.h"

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "calib-convert");
	fprintf(out,
"Reads the camera calibration IN, prints what it holds, and writes it to OUT.\n"
"\n"
"IN may be (recognised by content):\n"
"  mvod JSON             \"format\": \"mvod-calibration/1\"\n"
"  JSON [K, dist] pair   [[[fx,0,cx],[0,fy,cy],[0,0,1]], [k1,k2,p1,p2,k3]], or\n"
"                        {\"K\": ..., \"dist\": ..., \"model\": \"fisheye-kb4\"} (model optional)\n"
"  OpenCV FileStorage    YAML or XML with camera_matrix and distortion_coefficients\n"
"                        (image_width, image_height optional), as OpenCV's calibration samples\n"
"                        write them; M1 and D1 of OpenCV's stereo sample; 4 coefficients are\n"
"                        k1 k2 p1 p2 unless the file says distortion_model: fisheye\n"
"  ROS camera_info YAML  distortion_model plumb_bob, rational_polynomial or equidistant\n"
"                        (fisheye)\n"
"  KITTI calib.txt       fx, fy, cx, cy from P0 (no distortion, no image size)\n"
"  DSO camera.txt        TUM monoVO's and DSO's: FOV fx fy cx cy w (or 5 bare numbers),\n"
"                        Pinhole, RadTan, EquiDistant or KannalaBrandt; relative or pixels\n"
"The camera's mount (mvod mount) is carried between mvod JSON (its \"mount\" block),\n"
"OpenCV and ROS files (mount_height_m, mount_pitch_deg, mount_roll_deg); KITTI and DSO\n"
"drop it. The FOV lens goes to mvod JSON, OpenCV (distortion_model: fov) and DSO only.\n"
"\n"
"Options:\n"
"  --to FORMAT           mvod (JSON), opencv (YAML, or XML when OUT ends in .xml), ros\n"
"                        (camera_info YAML), kitti (calib.txt: P0..P3, distortion-free\n"
"                        cameras only) or dso (camera.txt, in pixels). Default from OUT's\n"
"                        name: .json mvod; .yml, .yaml and .xml opencv; camera.txt dso;\n"
"                        other .txt kitti. ROS and OpenCV share .yaml, so ROS output always\n"
"                        needs --to ros.\n"
"  --size WxH            image size in pixels, for an IN that does not record it (KITTI,\n"
"                        a [K, dist] pair, OpenCV stereo files); mvod, ros and dso output\n"
"                        need one\n"
"\n");
	cli_usage_general(out);
	fprintf(out,
"Example:\n"
"  mvod calib-convert ~/.ros/camera_info/cam.yaml calib.json\n"
"  mvod calib-convert calib.json cam.yaml --to ros\n"
"\n"
"OUT is replaced whole or not at all. Exit status: 0 on success, 1 when IN cannot be read or\n"
"OUT cannot be written, 2 on a usage error (OUT refused at start: a folder, IN itself).\n");
}

enum convert_opt_id { OPT_TO = CLI_OPT_OWN, OPT_SIZE };

static const struct option convert_opts[] = {
	{"to", required_argument, NULL, OPT_TO},
	{"size", required_argument, NULL, OPT_SIZE},
	{NULL, 0, NULL, 0},
};

struct convert {
	const char *in, *out;
	enum mvod_calib_format to;
	int to_given;
	int width, height; /* 0: not given */
};

static int parse_size(const char *arg, struct convert *c)
{
	char *end;
	long w = strtol(arg, &end, 10), h = 0;
	if (*end == 'x')
		h = strtol(end + 1, &end, 10);
	if (*end || w < 1 || h < 1 || w > 65535 || h > 65535)
		return cli_bad_value("size", arg, "WIDTHxHEIGHT in pixels, e.g. 640x480");
	c->width = (int)w;
	c->height = (int)h;
	return 0;
}

static int parse_own(int id, const char *arg, void *ctx)
{
	struct convert *c = ctx;
	switch (id) {
	case OPT_TO:
		c->to_given = 1;
		if (mvod_calib_format_parse(arg, &c->to) || c->to == MVOD_CALIB_FMT_PAIR)
			return cli_bad_value("to", arg, "mvod, opencv, ros, kitti or dso");
		return 0;
	case OPT_SIZE:
		return parse_size(arg, c);
	}
	return -ENOENT;
}

static int format_from_name(const char *path, enum mvod_calib_format *fmt)
{
	if (cli_has_suffix(path, ".json"))
		*fmt = MVOD_CALIB_FMT_MVOD;
	else if (cli_has_suffix(path, ".yml") || cli_has_suffix(path, ".yaml") || cli_has_suffix(path, ".xml"))
		*fmt = MVOD_CALIB_FMT_OPENCV;
	else if (cli_has_suffix(path, "/camera.txt") || strcmp(path, "camera.txt") == 0)
		*fmt = MVOD_CALIB_FMT_DSO;
	else if (cli_has_suffix(path, ".txt"))
		*fmt = MVOD_CALIB_FMT_KITTI;
	else
		return -EINVAL;
	return 0;
}

static int parse_cli(int argc, char **argv, struct convert *c)
{
	int quiet = 0;
	const char *files[2];
	int ret = cli_getopt_args(argc, argv, convert_opts, parse_own, c, usage, NULL, &quiet, files,
				  2, "IN and OUT, e.g. mvod calib-convert cam.yaml calib.json");
	if (ret)
		return ret;
	c->in = files[0];
	c->out = files[1];
	if (!c->to_given && format_from_name(c->out, &c->to)) {
		fprintf(stderr, "%s: cannot tell the format from the name %s: give --to "
				"mvod|opencv|ros|kitti|dso\n", cli_prog, c->out);
		return -EINVAL;
	}
	return 0;
}

static void print_camera(const char *path, enum mvod_calib_format fmt, const struct mvod_camera *cam)
{
	printf("read %s (%s): %s, ", path, mvod_calib_format_title(fmt), mvod_cam_model_name(cam->model));
	if (cam->width > 0)
		printf("%dx%d", cam->width, cam->height);
	else
		printf("image size not recorded");
	printf("\n  fx %.10g  fy %.10g  cx %.10g  cy %.10g\n  distortion [", cam->fx, cam->fy, cam->cx,
	       cam->cy);
	for (int i = 0; i < cam->n_dist; i++)
		printf("%s%.10g", i ? ", " : "", cam->dist[i]);
	printf("]\n");
	if (cam->has_mount)
		printf("  mount: height %.10g m, pitch %.10g deg, roll %.10g deg\n", cam->mount_height_m,
		       cam->mount_pitch_deg, cam->mount_roll_deg);
}

/* --size fills in a size IN lacks; it must not contradict one IN records. */
static int apply_size(const struct convert *c, struct mvod_camera *cam)
{
	if (c->width && cam->width && (c->width != cam->width || c->height != cam->height)) {
		fprintf(stderr, "%s: %s is for %dx%d images, not --size %dx%d\n", cli_prog, c->in,
			cam->width, cam->height, c->width, c->height);
		return EXIT_USAGE;
	}
	if (c->width) {
		cam->width = c->width;
		cam->height = c->height;
	}
	if (!cam->width && (c->to == MVOD_CALIB_FMT_MVOD || c->to == MVOD_CALIB_FMT_ROS ||
			    c->to == MVOD_CALIB_FMT_DSO)) {
		fprintf(stderr, "%s: %s does not record the image size, which %s output needs: give "
				"--size WxH\n", cli_prog, c->in, mvod_calib_format_title(c->to));
		return EXIT_USAGE;
	}
	return 0;
}

static int save(const struct convert *c, const struct mvod_camera *cam, char *err, size_t errlen)
{
	switch (c->to) {
	case MVOD_CALIB_FMT_OPENCV: return mvod_calib_save_opencv(c->out, cam, err, errlen);
	case MVOD_CALIB_FMT_ROS: return mvod_calib_save_ros(c->out, cam, err, errlen);
	case MVOD_CALIB_FMT_KITTI:
	case MVOD_CALIB_FMT_DSO:
		if (cam->has_mount)
			fprintf(stderr, "%s: note: %s has no place for the mount: it is not carried "
				"into %s\n", cli_prog, mvod_calib_format_title(c->to), c->out);
		return (c->to == MVOD_CALIB_FMT_DSO ? mvod_calib_save_dso
						    : mvod_calib_save_kitti)(c->out, cam, err, errlen);
	default: break;
	}
	struct mvod_calib_meta meta = {.rms_px = -1};
	snprintf(meta.source, sizeof(meta.source), "mvod calib-convert from %s", c->in);
	int ret = mvod_calib_save(c->out, cam, &meta);
	if (ret)
		snprintf(err, errlen, "cannot write %s: %s", c->out, strerror(-ret));
	return ret;
}

int mvod_cmd_convert(int argc, char **argv)
{
	struct convert c = {0};
	int ret = parse_cli(argc, argv, &c);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	struct mvod_camera cam;
	enum mvod_calib_format from;
	char err[MVOD_ERR_MAX];
	if (mvod_calib_load_format(c.in, &cam, &from, err, sizeof(err))) {
		fprintf(stderr, "%s: %s\n", cli_prog, err);
		return 1;
	}
	print_camera(c.in, from, &cam);
	/* IN is noted as an input now: OUT may not be it, nor a directory, nor a disk. */
	if (cli_check_writable("OUT", c.out))
		return EXIT_USAGE;
	ret = apply_size(&c, &cam);
	if (ret)
		return ret;
	if (save(&c, &cam, err, sizeof(err))) {
		fprintf(stderr, "%s: %s\n", cli_prog, err);
		return 1;
	}
	printf("wrote %s (%s)\n", c.out, mvod_calib_format_title(c.to));
	return 0;
}
