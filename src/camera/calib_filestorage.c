/*
 * OpenCV FileStorage YAML/XML and ROS camera_info YAML, read with libyaml and libxml2. A
 * calibration file is user input, and OpenCV's own FileStorage parser over-reads and loops
 * forever on malformed text (opencv#28619, opencv#21851); these two parsers are fuzzed
 * upstream and bound their own work. Only the keys a camera needs are looked at, each as a
 * node of whichever syntax the text was.
 */
#include "mvod/calib.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <yaml.h>

#include "camera/calib_internal.h"
#include "util/cvyaml.h"
#include "util/errbuf.h"
#include "util/text_guard.h"

#define UNKNOWN_FORMAT                                                                            \
	"unknown calibration format: not mvod JSON, a [K, dist] JSON pair, KITTI calib.txt, "      \
	"DSO camera.txt, OpenCV YAML/XML or ROS camera_info YAML"

/* A YAML node (with its document, which resolves its children) or an XML element; none when absent. */
struct fs_node {
	yaml_document_t *doc;
	yaml_node_t *y;
	xmlNode *x;
};

static bool present(struct fs_node n)
{
	return n.y || n.x;
}

/* An XML element is a map when it holds elements; its text is a scalar otherwise. */
static bool is_map(struct fs_node n)
{
	if (n.y)
		return n.y->type == YAML_MAPPING_NODE;
	for (xmlNode *c = n.x ? n.x->children : NULL; c; c = c->next)
		if (c->type == XML_ELEMENT_NODE)
			return true;
	return false;
}

/* A map's value under key (the first, if the key repeats). */
static struct fs_node child(struct fs_node map, const char *key)
{
	struct fs_node out = {.doc = map.doc};
	if (map.y)
		out.y = mvod_cvyaml_child(map.doc, map.y, key);
	for (xmlNode *c = map.x ? map.x->children : NULL; c && !out.x; c = c->next)
		if (c->type == XML_ELEMENT_NODE && xmlStrEqual(c->name, BAD_CAST key))
			out.x = c;
	return out;
}

/*
 * A scalar's text, for xmlFree (libxml2 hands out XML text that way, so YAML's is allocated
 * alike rather than copied twice); NULL when the node is absent or not a scalar. *plain:
 * whether it may be a number (YAML's quoted strings are not; XML has no quoting). The text is
 * at most a calibration file long (4 MiB), so its length fits an int.
 */
static char *scalar(struct fs_node n, bool *plain)
{
	if (n.y) {
		const yaml_node_t *y = n.y;
		if (y->type != YAML_SCALAR_NODE || memchr(y->data.scalar.value, 0, y->data.scalar.length))
			return NULL;
		*plain = y->data.scalar.style == YAML_PLAIN_SCALAR_STYLE;
		return (char *)xmlStrndup(y->data.scalar.value, (int)y->data.scalar.length);
	}
	if (!n.x || is_map(n))
		return NULL;
	*plain = true;
	return (char *)xmlNodeGetContent(n.x);
}

/* The text with the whitespace around it, as XML may have, ignored. */
static bool all_space(const char *s)
{
	return s[strspn(s, " \t\r\n")] == '\0';
}

static bool read_int(struct fs_node n, long lo, long hi, int *out)
{
	bool plain = false;
	char *s = scalar(n, &plain), *end = s;
	long v = s && plain ? strtol(s, &end, 10) : 0;
	bool ok = s && end != s && all_space(end) && v >= lo && v <= hi;
	xmlFree(s);
	if (ok)
		*out = (int)v;
	return ok;
}

/* OpenCV XML's data: text of numbers between whitespace. */
static int xml_numbers(struct fs_node data, struct mvod_cvyaml_numbers *m)
{
	bool plain;
	char *text = scalar(data, &plain), *save = NULL;
	*m = mvod_cvyaml_numbers_into(m->v, m->cap);
	if (!text)
		return -EINVAL;
	for (char *t = strtok_r(text, " \t\r\n", &save); t; t = strtok_r(NULL, " \t\r\n", &save))
		mvod_cvyaml_take(m, t, strlen(t));
	xmlFree(text);
	return 0;
}

/* OpenCV XML's matrix: the YAML one's elements, rows, cols and data. */
static int xml_matrix(struct fs_node node, int *rows, int *cols, struct mvod_cvyaml_numbers *m,
		      char *why, size_t whylen)
{
	if (!is_map(node) || !read_int(child(node, "rows"), INT_MIN, INT_MAX, rows) ||
	    !read_int(child(node, "cols"), INT_MIN, INT_MAX, cols) || xml_numbers(child(node, "data"), m))
		return mvod_errf(why, whylen, -EINVAL, "must be a matrix with rows, cols and data");
	return mvod_cvyaml_matrix_check(*rows, *cols, m, why, whylen);
}

/*
 * A matrix: rows, cols and rows*cols finite numbers in data, the first MVOD_MAX_DIST of them in
 * m. OpenCV's !!opencv-matrix, its XML twin and ROS's plain maps all have this shape.
 */
static int read_matrix(struct fs_node node, const char *key, int *rows, int *cols,
		       struct mvod_cvyaml_numbers *m, char *err, size_t errlen)
{
	char why[128];
	size_t line;
	if (!present(node))
		return mvod_errf(err, errlen, -EINVAL, "no \"%s\" key", key);
	int ret = node.y ? mvod_cvyaml_matrix(node.doc, node.y, rows, cols, m, &line, why, sizeof(why))
			 : xml_matrix(node, rows, cols, m, why, sizeof(why));
	return ret ? mvod_errf(err, errlen, ret, "\"%s\": %s", key, why) : 0;
}

static int read_size(struct fs_node root, const char *key, int *out, char *err, size_t errlen)
{
	struct fs_node n = child(root, key);
	if (present(n) && !read_int(n, 0, 65535, out))
		return mvod_errf(err, errlen, -EINVAL, "\"%s\" must be a whole number of pixels", key);
	return 0;
}

/* ROS names, Kalibr's and mvod's own. */
static int read_model(struct fs_node root, enum mvod_cam_model *model, char *err, size_t errlen)
{
	struct fs_node n = child(root, "distortion_model");
	if (!present(n))
		return 0;
	static const struct {
		const char *name;
		enum mvod_cam_model model;
	} names[] = {
		{"plumb_bob", MVOD_CAM_PINHOLE_RADTAN},  {"rational_polynomial", MVOD_CAM_PINHOLE_RADTAN},
		{"radtan", MVOD_CAM_PINHOLE_RADTAN},     {"pinhole-radtan", MVOD_CAM_PINHOLE_RADTAN},
		{"equidistant", MVOD_CAM_FISHEYE_KB4},   {"fisheye", MVOD_CAM_FISHEYE_KB4},
		{"fisheye-kb4", MVOD_CAM_FISHEYE_KB4},   {"fov", MVOD_CAM_FOV},
	};
	bool plain;
	char *name = scalar(n, &plain);
	size_t i = 0;
	while (name && i < sizeof(names) / sizeof(names[0]) && strcmp(name, names[i].name) != 0)
		i++;
	bool known = name && i < sizeof(names) / sizeof(names[0]);
	xmlFree(name);
	if (!known)
		return mvod_errf(err, errlen, -EINVAL,
				 "\"distortion_model\" must be plumb_bob, rational_polynomial, equidistant, "
				 "fisheye or fov");
	*model = names[i].model;
	return 0;
}

/*
 * The mount, as three top-level scalars rather than a "mount" map: OpenCV writes and reads
 * flat keys like image_width the same way in YAML and XML, and mvod mount replaces a scalar's
 * text in place, keeping every other byte of the file (see mvod_calib_filestorage_set_mount).
 */
const char *const mvod_calib_mount_keys[3] = {"mount_height_m", "mount_pitch_deg",
						"mount_roll_deg"};

static bool read_double(struct fs_node n, double *out)
{
	bool plain = false;
	char *s = scalar(n, &plain), *end = s;
	double v = s && plain ? strtod(s, &end) : 0;
	bool ok = s && end != s && all_space(end) && isfinite(v);
	xmlFree(s);
	if (ok)
		*out = v;
	return ok;
}

/* Optional; the same bounds as mvod JSON's "mount" block. Pitch and roll default to 0. */
static int read_mount(struct fs_node root, struct mvod_camera *c, char *err, size_t errlen)
{
	double v[3] = {0, 0, 0};
	bool any = false, ok = true;
	for (int i = 0; i < 3; i++) {
		struct fs_node n = child(root, mvod_calib_mount_keys[i]);
		any = any || present(n);
		ok = ok && (!present(n) || read_double(n, &v[i]));
	}
	if (!any)
		return 0;
	if (!ok || !present(child(root, mvod_calib_mount_keys[0])) ||
	    !mvod_calib_mount_ok(v[0], v[1], v[2]))
		return mvod_errf(err, errlen, -EINVAL,
				 "the mount must be \"mount_height_m\": metres above the ground, in "
				 "(0, %g], \"mount_pitch_deg\": degrees down, \"mount_roll_deg\": "
				 "degrees, each within +-%g: correct them or remove them",
				 MVOD_MOUNT_MAX_HEIGHT_M, MVOD_MOUNT_MAX_ANGLE_DEG);
	c->has_mount = true;
	c->mount_height_m = v[0];
	c->mount_pitch_deg = v[1];
	c->mount_roll_deg = v[2];
	return 0;
}

static int read_camera(struct fs_node root, struct mvod_camera *c, char *err, size_t errlen)
{
	/* OpenCV's stereo_calib sample writes M1 D1 M2 D2: the first camera is the one wanted. */
	struct fs_node k = child(root, "camera_matrix");
	const bool stereo = !present(k) && present(k = child(root, "M1"));
	const char *kkey = stereo ? "M1" : "camera_matrix", *dkey = stereo ? "D1" : "distortion_coefficients";
	int rows, cols, ret;
	double v[MVOD_MAX_DIST];
	struct mvod_cvyaml_numbers m = mvod_cvyaml_numbers_into(v, MVOD_MAX_DIST);
	if ((ret = read_size(root, "image_width", &c->width, err, errlen)) ||
	    (ret = read_size(root, "image_height", &c->height, err, errlen)) ||
	    (ret = read_model(root, &c->model, err, errlen)))
		return ret;
	if (!present(k))
		return mvod_errf(err, errlen, -EINVAL,
				 "unknown calibration format: no \"camera_matrix\" key, so not OpenCV or ROS "
				 "YAML (mvod also reads mvod JSON, [K, dist] JSON, KITTI calib.txt and DSO "
				 "camera.txt)");
	if ((ret = read_matrix(k, kkey, &rows, &cols, &m, err, errlen)))
		return ret;
	if (rows != 3 || cols != 3 || mvod_calib_set_K(v, c) != 0)
		return mvod_errf(err, errlen, -EINVAL,
				 "\"%s\" must be 3x3 [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0", kkey);
	if ((ret = read_matrix(child(root, dkey), dkey, &rows, &cols, &m, err, errlen)))
		return ret;
	if ((rows > 1 && cols > 1) || m.count > MVOD_MAX_DIST ||
	    !mvod_calib_dist_count_ok(c->model, (int)m.count))
		return mvod_errf(err, errlen, -EINVAL, "\"%s\" must be 1xN or Nx1 with N = %s for %s (not %dx%d)",
				 dkey, mvod_calib_dist_counts(c->model), mvod_cam_model_name(c->model), rows, cols);
	c->n_dist = (int)m.count;
	memcpy(c->dist, v, sizeof(double) * m.count);
	return read_mount(root, c, err, errlen);
}

/* The text's first YAML document (util/cvyaml.c), its syntax error worded as calib's. */
static int load_yaml(const char *text, yaml_document_t *doc, char *err, size_t errlen)
{
	char why[256];
	int ret = mvod_cvyaml_load(text, doc, why, sizeof(why));
	if (ret == -EINVAL)
		return mvod_errf(err, errlen, ret, UNKNOWN_FORMAT " (%s)", why);
	return ret ? mvod_errf(err, errlen, ret, "%s", why) : 0;
}

/*
 * Without a DOCTYPE there are no entities to expand and no DTD to fetch; OpenCV never writes
 * one. XML_PARSE_NONET besides, and no XML_PARSE_NOENT or XML_PARSE_DTDLOAD.
 */
static int load_xml(const char *text, xmlDoc **doc, char *err, size_t errlen)
{
	size_t len = strlen(text);
	if (strstr(text, "<!DOCTYPE"))
		return mvod_errf(err, errlen, -EINVAL, "XML with a DOCTYPE is not OpenCV's: refused");
	int ret = mvod_text_guard(text, len, MVOD_TEXT_XML, err, errlen);
	if (ret)
		return ret;
	xmlResetLastError();
	*doc = xmlReadMemory(text, (int)len, NULL, NULL, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
	if (!*doc) {
		const xmlError *e = xmlGetLastError();
		const char *msg = e && e->message ? e->message : "?";
		return mvod_errf(err, errlen, -EINVAL, UNKNOWN_FORMAT " (XML error at line %d: %.*s)",
				 e ? e->line : 0, (int)strcspn(msg, "\n"), msg);
	}
	const xmlNode *root = xmlDocGetRootElement(*doc);
	if (!root || !xmlStrEqual(root->name, BAD_CAST "opencv_storage")) {
		xmlFreeDoc(*doc);
		return mvod_errf(err, errlen, -EINVAL, UNKNOWN_FORMAT " (XML whose root is not <opencv_storage>)");
	}
	return 0;
}

int mvod_calib_parse_filestorage(const char *text, struct mvod_camera *cam, enum mvod_calib_format *fmt,
				 char *err, size_t errlen)
{
	const char *p = text + strspn(text, " \t\r\n");
	const bool xml = *p == '<', opencv_yaml = strncmp(p, "%YAML:", 6) == 0;
	yaml_document_t ydoc;
	xmlDoc *xdoc = NULL;
	int ret = xml ? load_xml(p, &xdoc, err, errlen)
		      : load_yaml(text, &ydoc, err, errlen);
	if (ret)
		return ret;
	struct fs_node root = {.doc = xml ? NULL : &ydoc};
	if (xml)
		root.x = xmlDocGetRootElement(xdoc);
	else
		root.y = yaml_document_get_root_node(&ydoc);
	struct mvod_camera c = {.model = MVOD_CAM_PINHOLE_RADTAN};
	ret = read_camera(root, &c, err, errlen);
	if (xml)
		xmlFreeDoc(xdoc);
	else
		yaml_document_delete(&ydoc);
	if (ret)
		return ret;
	*cam = c;
	if (fmt)
		*fmt = xml || opencv_yaml ? MVOD_CALIB_FMT_OPENCV : MVOD_CALIB_FMT_ROS;
	return 0;
}

/* A replacement of text[at, end) by s (an insertion when at == end). */
struct fs_edit {
	size_t at, end;
	char s[256];
};

/*
 * libyaml's marks count characters (a CRLF two), not bytes: the byte offset of character i
 * of the UTF-8 text, after the byte-order mark that libyaml skips uncounted.
 */
static size_t byte_at(const char *text, size_t i)
{
	size_t b = strncmp(text, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
	for (; text[b] && i > 0; i--)
		do
			b++;
		while (((unsigned char)text[b] & 0xC0) == 0x80);
	return b;
}

/* The shortest decimal that reads back as v, appended to s (of size n). */
static void add_number(char *s, size_t n, double v)
{
	char buf[32];
	for (int digits = 15; digits <= 17; digits++) {
		snprintf(buf, sizeof(buf), "%.*g", digits, v);
		if (strtod(buf, NULL) == v)
			break;
	}
	strncat(s, buf, n - strlen(s) - 1);
}

/*
 * The edits that set the mount in the YAML document: a key already there has its value's
 * text replaced; the others are added, one line each at the first key's indentation, where
 * the top-level map ends (after its last entry and any comment after it). At most 4 edits.
 */
static int mount_edits(const char *text, yaml_document_t *doc, const double mount[3],
		       struct fs_edit *e, int *n, char *err, size_t errlen)
{
	yaml_node_t *root = yaml_document_get_root_node(doc);
	if (!root || root->type != YAML_MAPPING_NODE ||
	    root->data.mapping.style != YAML_BLOCK_MAPPING_STYLE ||
	    root->data.mapping.pairs.start == root->data.mapping.pairs.top)
		return mvod_errf(err, errlen, -ENOTSUP, "the camera file's YAML is not a block map of "
				 "keys (one per line), the layout the mount can be added to");
	const yaml_node_t *first = yaml_document_get_node(doc, root->data.mapping.pairs.start->key);
	struct fs_node r = {.doc = doc, .y = root};
	struct fs_edit *add = &e[0];
	size_t end = byte_at(text, root->end_mark.index);
	*add = (struct fs_edit){.at = end, .end = end};
	if (end > 0 && text[end - 1] != '\n')
		strcat(add->s, "\n");
	*n = 1;
	for (int i = 0; i < 3; i++) {
		struct fs_node v = child(r, mvod_calib_mount_keys[i]);
		if (v.y && v.y->type != YAML_SCALAR_NODE)
			return mvod_errf(err, errlen, -EINVAL, "\"%s\" must be a number",
					 mvod_calib_mount_keys[i]);
		if (v.y) {
			e[*n] = (struct fs_edit){.at = byte_at(text, v.y->start_mark.index),
						 .end = byte_at(text, v.y->end_mark.index)};
			add_number(e[(*n)++].s, sizeof(e->s), mount[i]);
			continue;
		}
		size_t len = strlen(add->s);
		snprintf(add->s + len, sizeof(add->s) - len, "%*s%s: ", (int)first->start_mark.column, "",
			 mvod_calib_mount_keys[i]);
		add_number(add->s, sizeof(add->s), mount[i]);
		strncat(add->s, "\n", sizeof(add->s) - strlen(add->s) - 1);
	}
	if (add->s[0] == '\n' && add->s[1] == '\0')
		add->s[0] = '\0';
	return 0;
}

/* text with the edits applied, in the order of their place; malloc'd into *out. */
static int apply_edits(const char *text, struct fs_edit *e, int n, char **out)
{
	for (int i = 1; i < n; i++)
		for (int j = i; j > 0 && e[j].at < e[j - 1].at; j--) {
			struct fs_edit t = e[j];
			e[j] = e[j - 1];
			e[j - 1] = t;
		}
	size_t len = strlen(text) + 1;
	for (int i = 0; i < n; i++)
		len += strlen(e[i].s);
	char *s = malloc(len);
	if (!s)
		return -ENOMEM;
	size_t from = 0, to = 0;
	for (int i = 0; i < n; i++) {
		memcpy(s + to, text + from, e[i].at - from);
		to += e[i].at - from;
		memcpy(s + to, e[i].s, strlen(e[i].s));
		to += strlen(e[i].s);
		from = e[i].end;
	}
	strcpy(s + to, text + from);
	*out = s;
	return 0;
}

/* Whether b is a with the mount m, as read back. */
static bool same_but_mount(const struct mvod_camera *a, const struct mvod_camera *b,
			   const double m[3])
{
	return a->model == b->model && a->width == b->width && a->height == b->height && a->fx == b->fx &&
	       a->fy == b->fy && a->cx == b->cx && a->cy == b->cy && a->n_dist == b->n_dist &&
	       memcmp(a->dist, b->dist, sizeof(double) * (size_t)a->n_dist) == 0 && b->has_mount &&
	       b->mount_height_m == m[0] && b->mount_pitch_deg == m[1] && b->mount_roll_deg == m[2];
}

/*
 * The edit is checked by reading it back: a file is never written that would not read as the
 * same camera with the mount m. On a refusal *out is freed and NULL.
 */
static int read_back(const struct mvod_camera *before, const double m[3], char **out, char *err,
		     size_t errlen)
{
	struct mvod_camera after;
	char why[256];
	if (!mvod_calib_parse_filestorage(*out, &after, NULL, why, sizeof(why)) &&
	    same_but_mount(before, &after, m))
		return 0;
	free(*out);
	*out = NULL;
	return mvod_errf(err, errlen, -EINVAL, "the camera file with the mount set would not read "
			 "back as the same camera: nothing written");
}

/*
 * The mount set in an OpenCV XML file, through libxml2's tree: an element already at the top
 * level has its text replaced, the others are added after the last one, each after a copy of
 * the blank text that leads the root's first element (OpenCV's newline), so that the file keeps
 * its layout: libxml2 writes back the whitespace, comments and text it read, and OpenCV's own
 * XML (double-quoted attributes, no empty elements) byte for byte but for the mount.
 */
static int xml_set_mount(const char *text, const double mount[3], char **out, char *err,
			 size_t errlen)
{
	xmlDoc *doc;
	int ret = load_xml(text, &doc, err, errlen);
	if (ret)
		return ret;
	xmlNode *root = xmlDocGetRootElement(doc);
	const xmlChar *lead = BAD_CAST "\n";
	for (xmlNode *c = root->children; c; c = c->next)
		if (c->type == XML_ELEMENT_NODE) {
			if (c->prev && xmlIsBlankNode(c->prev))
				lead = c->prev->content;
			break;
		}
	/* New elements go before the blank text that closes the root, if there is one. */
	xmlNode *tail = root->last && xmlIsBlankNode(root->last) ? root->last : NULL;
	for (int i = 0; i < 3 && !ret; i++) {
		char v[32] = "";
		add_number(v, sizeof(v), mount[i]);
		struct fs_node have = child((struct fs_node){.x = root}, mvod_calib_mount_keys[i]);
		if (have.x) {
			xmlNodeSetContent(have.x, BAD_CAST v);
			continue;
		}
		xmlNode *gap = xmlNewText(lead), *el = xmlNewNode(NULL, BAD_CAST mvod_calib_mount_keys[i]);
		if (!gap || !el) {
			xmlFreeNode(gap);
			xmlFreeNode(el);
			ret = -ENOMEM;
			break;
		}
		xmlNodeSetContent(el, BAD_CAST v);
		/* The element first: libxml2 merges a text node into a text neighbour (and frees it). */
		if (tail)
			xmlAddPrevSibling(tail, el);
		else
			xmlAddChild(root, el);
		xmlAddPrevSibling(el, gap);
	}
	xmlChar *buf = NULL;
	int len = 0;
	if (!ret)
		xmlDocDumpMemory(doc, &buf, &len);
	xmlFreeDoc(doc);
	if (!ret && (!buf || !(*out = strndup((const char *)buf, (size_t)len))))
		ret = -ENOMEM;
	xmlFree(buf);
	return ret ? mvod_errf(err, errlen, ret, "out of memory") : 0;
}

int mvod_calib_filestorage_set_mount(const char *text, const double mount[3], char **out, char *err,
				     size_t errlen)
{
	const char *p = text + strspn(text, " \t\r\n");
	struct mvod_camera before;
	int ret = mvod_calib_parse_filestorage(text, &before, NULL, err, errlen);
	if (ret)
		return ret;
	if (*p == '<') {
		if ((ret = xml_set_mount(p, mount, out, err, errlen)))
			return ret;
		return read_back(&before, mount, out, err, errlen);
	}
	yaml_document_t doc;
	if ((ret = load_yaml(text, &doc, err, errlen)))
		return ret;
	struct fs_edit e[4];
	int n = 0;
	ret = mount_edits(text, &doc, mount, e, &n, err, errlen);
	yaml_document_delete(&doc);
	if (!ret && (ret = apply_edits(text, e, n, out)))
		return mvod_errf(err, errlen, ret, "out of memory");
	return ret ? ret : read_back(&before, mount, out, err, errlen);
}
