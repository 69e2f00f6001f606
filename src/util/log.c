#include "mvod/log.h"

#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <systemd/sd-daemon.h>

static enum mvod_log_level current_level = MVOD_LOG_INFO;
static pthread_once_t journal_once = PTHREAD_ONCE_INIT;
static bool journal;

const char *const mvod_log_level_names[] = {"error", "warn", "info", "debug", NULL};

void mvod_log_set_level(enum mvod_log_level level)
{
	current_level = level;
}

enum mvod_log_level mvod_log_get_level(void)
{
	return current_level;
}

bool mvod_log_is_journal(const char *journal_stream, int fd)
{
	unsigned long long dev, ino;
	char extra;
	struct stat st;
	if (!journal_stream || sscanf(journal_stream, "%llu:%llu%c", &dev, &ino, &extra) != 2)
		return false;
	return fstat(fd, &st) == 0 && st.st_dev == dev && st.st_ino == ino;
}

static void detect_journal(void)
{
	/* stderr redirected elsewhere (a file, a pipe) under systemd keeps the plain format. */
	journal = mvod_log_is_journal(getenv("JOURNAL_STREAM"), STDERR_FILENO);
}

void mvod_log_set_journal(bool on)
{
	pthread_once(&journal_once, detect_journal);
	journal = on;
}

void mvod_log(enum mvod_log_level level, const char *fmt, ...)
{
	static const char *const priority[] = {SD_ERR, SD_WARNING, SD_INFO, SD_DEBUG};
	if (level > current_level)
		return;
	pthread_once(&journal_once, detect_journal);
	/* One fputs of a whole line, so lines from threads never interleave. */
	char line[1024];
	int n = snprintf(line, sizeof(line), "%s%s: ", journal ? priority[level] : "mvod: ",
			 mvod_log_level_names[level]);
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line + n, sizeof(line) - (size_t)n - 1, fmt, ap);
	va_end(ap);
	size_t len = strlen(line);
	line[len] = '\n';
	line[len + 1] = '\0';
	fputs(line, stderr);
}
