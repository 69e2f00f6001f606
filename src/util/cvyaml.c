#include "util/cvyaml.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "util/errbuf.h"
#include "util/text_guard.h"

struct mvod_cvyaml_numbers mvod_cvyaml_numbers_into(double *v, size_t cap)
{
	return (struct mvod_cvyaml_numbers){.v = v, .cap = cap, .bad = SIZE_MAX};
}

static int yaml_error(const yaml_parser_t *p, char *why, size_t whylen)
{
	if (p->error == YAML_MEMORY_ERROR)
		return mvod_errf(why, whylen, -ENOMEM, "out of memory reading the YAML");
	/* The reader (bad UTF-8, say) marks no line, only the byte. */
	if (p->error == YAML_READER_ERROR)
		return mvod_errf(why, whylen, -EINVAL, "YAML error at byte %zu: %s",
				 p->problem_offset, p->problem ? p->problem : "?");
	return mvod_errf(why, whylen, -EINVAL, "YAML error at line %zu: %s",
			 p->problem_mark.line + 1, p->problem ? p->problem : "?");
}

/* Where OpenCV's "%YAML:" line starts in text, or SIZE_MAX when it has none. */
static size_t opencv_directive(const char *text)
{
	const char *p = text + (strncmp(text, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0);
	p += strspn(p, " \t\r\n");
	return strncmp(p, "%YAML:", 6) == 0 ? (size_t)(p - text) : SIZE_MAX;
}

int mvod_cvyaml_load(const char *text, yaml_document_t *doc, char *why, size_t whylen)
{
	char *copy = strdup(text);
	yaml_parser_t parser;
	if (!copy || !yaml_parser_initialize(&parser)) {
		free(copy);
		return mvod_errf(why, whylen, -ENOMEM, "out of memory reading the YAML");
	}
	size_t at = opencv_directive(copy), len = strlen(copy);
	if (at != SIZE_MAX)
		copy[at] = '#';
	yaml_parser_set_input_string(&parser, (const unsigned char *)copy, len);
	/* The guard first: libyaml's cost grows with the square of the nesting (text_guard.h). */
	int ret = mvod_text_guard(copy, len, MVOD_TEXT_YAML, why, whylen);
	if (!ret && !yaml_parser_load(&parser, doc))
		ret = yaml_error(&parser, why, whylen);
	for (bool more = ret == 0 && yaml_document_get_root_node(doc); more && ret == 0;) {
		yaml_document_t next;
		if (!yaml_parser_load(&parser, &next)) {
			ret = yaml_error(&parser, why, whylen);
			yaml_document_delete(doc);
			break;
		}
		more = yaml_document_get_root_node(&next) != NULL;
		yaml_document_delete(&next);
	}
	yaml_parser_delete(&parser);
	free(copy);
	return ret;
}

static bool scalar_is(const yaml_node_t *n, const char *s)
{
	return n && n->type == YAML_SCALAR_NODE && n->data.scalar.length == strlen(s) &&
	       memcmp(n->data.scalar.value, s, n->data.scalar.length) == 0;
}

yaml_node_t *mvod_cvyaml_child(yaml_document_t *doc, const yaml_node_t *map, const char *key)
{
	if (!map || map->type != YAML_MAPPING_NODE)
		return NULL;
	for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
	     p++)
		if (scalar_is(yaml_document_get_node(doc, p->key), key))
			return yaml_document_get_node(doc, p->value);
	return NULL;
}

size_t mvod_cvyaml_line(const yaml_node_t *n)
{
	return n->start_mark.line + 1;
}

/* YAML's spellings of infinity and NaN, which strtod does not know. */
static bool yaml_nonfinite(const char *s)
{
	s += *s == '-' || *s == '+';
	return strcasecmp(s, ".inf") == 0 || strcasecmp(s, ".nan") == 0;
}

void mvod_cvyaml_take(struct mvod_cvyaml_numbers *m, const char *s, size_t len)
{
	char *end = (char *)s;
	double v = s ? strtod(s, &end) : 0;
	bool number = end != s && end == s + len;
	if ((!number || !isfinite(v)) && m->bad == SIZE_MAX) {
		m->bad = m->count;
		m->bad_is_number = number || (s && yaml_nonfinite(s));
	}
	if (m->count < m->cap)
		m->v[m->count] = v;
	m->count++;
}

/* A plain scalar: quoted text ("320") is a string to YAML and to OpenCV, never a number. */
static bool plain(const yaml_node_t *n)
{
	return n && n->type == YAML_SCALAR_NODE && n->data.scalar.style == YAML_PLAIN_SCALAR_STYLE &&
	       !memchr(n->data.scalar.value, 0, n->data.scalar.length);
}

int mvod_cvyaml_sequence(yaml_document_t *doc, const yaml_node_t *seq,
			 struct mvod_cvyaml_numbers *m)
{
	*m = mvod_cvyaml_numbers_into(m->v, m->cap);
	if (!seq || seq->type != YAML_SEQUENCE_NODE)
		return -EINVAL;
	for (yaml_node_item_t *i = seq->data.sequence.items.start; i < seq->data.sequence.items.top;
	     i++) {
		const yaml_node_t *v = yaml_document_get_node(doc, *i);
		bool p = plain(v);
		mvod_cvyaml_take(m, p ? (const char *)v->data.scalar.value : NULL,
				 p ? v->data.scalar.length : 0);
	}
	return 0;
}

int mvod_cvyaml_matrix_check(int rows, int cols, const struct mvod_cvyaml_numbers *m, char *why,
			     size_t whylen)
{
	if (rows < 0 || cols < 0 || (uint64_t)rows * (uint64_t)cols != m->count)
		return mvod_errf(why, whylen, -EINVAL, "data holds %zu numbers, not rows x cols = "
				 "%d x %d", m->count, rows, cols);
	if (m->bad != SIZE_MAX)
		return mvod_errf(why, whylen, -EINVAL, "entry %zu is not %s", m->bad,
				 m->bad_is_number ? "finite" : "a number");
	return 0;
}

/* A plain scalar holding a whole number that fits an int. */
static bool read_int(const yaml_node_t *n, int *out)
{
	if (!plain(n))
		return false;
	const char *s = (const char *)n->data.scalar.value;
	char *end;
	errno = 0;
	long v = strtol(s, &end, 10);
	if (end == s || *end || errno || v < INT_MIN || v > INT_MAX)
		return false;
	*out = (int)v;
	return true;
}

int mvod_cvyaml_matrix(yaml_document_t *doc, const yaml_node_t *map, int *rows, int *cols,
		       struct mvod_cvyaml_numbers *m, size_t *line, char *why, size_t whylen)
{
	const yaml_node_t *data = mvod_cvyaml_child(doc, map, "data");
	*line = mvod_cvyaml_line(map);
	if (!read_int(mvod_cvyaml_child(doc, map, "rows"), rows) ||
	    !read_int(mvod_cvyaml_child(doc, map, "cols"), cols) ||
	    mvod_cvyaml_sequence(doc, data, m) != 0)
		return mvod_errf(why, whylen, -EINVAL, "must be a matrix with rows, cols and data");
	*line = mvod_cvyaml_line(data);
	return mvod_cvyaml_matrix_check(*rows, *cols, m, why, whylen);
}
