#include "mvod/log.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static enum mvod_log_level current_level = MVOD_LOG_INFO;

static const char *const level_names[] = {"error", "warn", "info", "debug"};

void mvod_log_set_level(enum mvod_log_level level)
{
	current_level = level;
}

enum mvod_log_level mvod_log_get_level(void)
{
	return current_level;
}

int mvod_log_parse_level(const char *name, enum mvod_log_level *out)
{
	for (int i = 0; i < (int)(sizeof(level_names) / sizeof(level_names[0])); i++) {
		if (strcmp(name, level_names[i]) == 0) {
			*out = (enum mvod_log_level)i;
			return 0;
		}
	}
	return -EINVAL;
}

void mvod_log(enum mvod_log_level level, const char *fmt, ...)
{
	if (level > current_level)
		return;
	/* One fputs of a whole line, so lines from threads never interleave. */
	char line[1024];
	int n = snprintf(line, sizeof(line), "mvod: %s: ", level_names[level]);
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line + n, sizeof(line) - (size_t)n - 1, fmt, ap);
	va_end(ap);
	size_t len = strlen(line);
	line[len] = '\n';
	line[len + 1] = '\0';
	fputs(line, stderr);
}
