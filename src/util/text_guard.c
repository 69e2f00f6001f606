#include "util/text_guard.h"

#include <errno.h>
#include <stdbool.h>
#include <string.h>

#include <yaml.h>

#include "util/errbuf.h"

static int too_deep(size_t line, char *err, size_t errlen)
{
	return mvod_errf(err, errlen, -ELOOP, "line %zu: nested more than %d levels deep (a camera "
			 "file nests 3): refused before parsing", line, MVOD_TEXT_MAX_DEPTH);
}

static int too_many(size_t line, const char *what, char *err, size_t errlen)
{
	return mvod_errf(err, errlen, -ELOOP, "line %zu: more than %d %s (a camera file has "
			 "none): refused before parsing", line, MVOD_TEXT_MAX_NAMES, what);
}

/*
 * YAML through libyaml's own event parser, which is linear while the depth is bounded and
 * which stops here at the first level too many, long before its scanner's cost (a loop over
 * every open flow level for each token) or its loader's (a search of every anchor before for
 * each anchor) grows. What libyaml cannot parse ends the scan: the parse that follows stops at
 * the same byte.
 */
static int guard_yaml(const char *text, size_t len, char *err, size_t errlen)
{
	yaml_parser_t p;
	if (!yaml_parser_initialize(&p))
		return mvod_errf(err, errlen, -ENOMEM, "out of memory reading the YAML");
	yaml_parser_set_input_string(&p, (const unsigned char *)text, len);
	int ret = 0, depth = 0, names = 0;
	for (bool end = false; !end && !ret;) {
		yaml_event_t e;
		if (!yaml_parser_parse(&p, &e))
			break;
		size_t line = e.start_mark.line + 1;
		end = e.type == YAML_STREAM_END_EVENT;
		bool seq = e.type == YAML_SEQUENCE_START_EVENT;
		bool map = e.type == YAML_MAPPING_START_EVENT;
		if (seq || map)
			ret = ++depth > MVOD_TEXT_MAX_DEPTH ? too_deep(line, err, errlen) : 0;
		if (e.type == YAML_SEQUENCE_END_EVENT || e.type == YAML_MAPPING_END_EVENT)
			depth--;
		bool named = e.type == YAML_ALIAS_EVENT ||
			     (e.type == YAML_SCALAR_EVENT && e.data.scalar.anchor) ||
			     (seq && e.data.sequence_start.anchor) ||
			     (map && e.data.mapping_start.anchor);
		if (!ret && named && ++names > MVOD_TEXT_MAX_NAMES)
			ret = too_many(line, "anchors and aliases", err, errlen);
		yaml_event_delete(&e);
	}
	yaml_parser_delete(&p);
	return ret;
}

/* Past the end of a quoted string that starts at s (its quote), counting lines. */
static const char *skip_quoted(const char *s, const char *end, bool escapes, size_t *line)
{
	char q = *s++;
	for (; s < end && *s != q; s++) {
		*line += *s == '\n';
		if (escapes && *s == '\\' && s + 1 < end)
			s++;
	}
	return s < end ? s + 1 : end;
}

/* JSON: brackets outside strings. cJSON recurses per level (to 1000). */
static int guard_json(const char *s, const char *end, char *err, size_t errlen)
{
	size_t line = 1;
	int depth = 0;
	while (s < end) {
		char c = *s;
		if (c == '"') {
			s = skip_quoted(s, end, true, &line);
			continue;
		}
		line += c == '\n';
		if ((c == '[' || c == '{') && ++depth > MVOD_TEXT_MAX_DEPTH)
			return too_deep(line, err, errlen);
		if ((c == ']' || c == '}') && depth > 0)
			depth--;
		s++;
	}
	return 0;
}

/* Past the first `close` at or after s, counting lines; end when there is none. */
static const char *skip_past(const char *s, const char *end, const char *close, size_t *line)
{
	size_t n = strlen(close);
	for (; s + n <= end; s++) {
		if (memcmp(s, close, n) == 0)
			return s + n;
		*line += *s == '\n';
	}
	return end;
}

/* An element's start tag from s ('<') past its '>': its attributes counted, *empty if "/>". */
static const char *skip_tag(const char *s, const char *end, size_t *line, int *attrs,
			    bool *empty)
{
	char prev = 0;
	*attrs = 0;
	for (s++; s < end && *s != '>'; s++) {
		if (*s == '"' || *s == '\'') {
			s = skip_quoted(s, end, false, line) - 1;
			continue;
		}
		*line += *s == '\n';
		*attrs += *s == '=';
		prev = *s;
	}
	*empty = prev == '/';
	return s < end ? s + 1 : end;
}

/* XML: elements open and not closed, and attributes of one element. */
static int guard_xml(const char *s, const char *end, char *err, size_t errlen)
{
	size_t line = 1;
	int depth = 0;
	while (s < end) {
		size_t left = (size_t)(end - s);
		if (*s != '<') {
			line += *s++ == '\n';
		} else if (left >= 4 && memcmp(s, "<!--", 4) == 0) {
			s = skip_past(s + 4, end, "-->", &line);
		} else if (left >= 9 && memcmp(s, "<![CDATA[", 9) == 0) {
			s = skip_past(s + 9, end, "]]>", &line);
		} else if (left >= 2 && (s[1] == '?' || s[1] == '!')) {
			s = skip_past(s + 2, end, s[1] == '?' ? "?>" : ">", &line);
		} else if (left >= 2 && s[1] == '/') {
			s = skip_past(s + 2, end, ">", &line);
			depth -= depth > 0;
		} else {
			int attrs;
			bool empty;
			size_t at = line;
			s = skip_tag(s, end, &line, &attrs, &empty);
			if (attrs > MVOD_TEXT_MAX_NAMES)
				return too_many(at, "attributes in one element", err, errlen);
			if (!empty && ++depth > MVOD_TEXT_MAX_DEPTH)
				return too_deep(at, err, errlen);
		}
	}
	return 0;
}

int mvod_text_guard(const char *text, size_t len, enum mvod_text_syntax syntax, char *err,
		    size_t errlen)
{
	if (len > MVOD_TEXT_MAX_BYTES)
		return mvod_errf(err, errlen, -EFBIG, "%zu bytes, more than the %zu of any camera "
				 "file: refused before parsing", len, MVOD_TEXT_MAX_BYTES);
	if (syntax == MVOD_TEXT_YAML)
		return guard_yaml(text, len, err, errlen);
	if (syntax == MVOD_TEXT_XML)
		return guard_xml(text, text + len, err, errlen);
	return guard_json(text, text + len, err, errlen);
}
