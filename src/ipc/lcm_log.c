#include "ipc/lcm_log.h"

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "util/output.h"

#define LOG_SYNC 0xEDA1DA01u

struct mvod_lcm_log {
	struct mvod_output *out;
	int64_t next_event;
	int error;
	size_t cap; /* of buf: MVOD_LCM_LOG_HEADER + the largest channel and message */
	uint8_t buf[];
};

int mvod_lcm_file_url(const char *url, char *path, size_t len, char *mode)
{
	static const char scheme[] = "file://";
	if (!url || strncmp(url, scheme, sizeof(scheme) - 1) != 0)
		return -ENOENT;
	const char *p = url + sizeof(scheme) - 1;
	size_t plen = strcspn(p, "?");
	/* LCM's mode option among &-separated options: r (its default), w or a. */
	*mode = 'r';
	for (const char *o = p[plen] ? p + plen : NULL; o; o = strchr(o + 1, '&'))
		if (strncmp(o + 1, "mode=", 5) == 0) {
			bool one = o[6] && (o[7] == '\0' || o[7] == '&');
			*mode = one && strchr("rwa", o[6]) ? o[6] : '?';
		}
	if (plen == 0)
		return -EINVAL;
	return (size_t)snprintf(path, len, "%.*s", (int)plen, p) < len ? 0 : -ENAMETOOLONG;
}

int mvod_lcm_log_open(const char *what, const char *path, size_t max_event,
		      struct mvod_lcm_log **out, char *err, size_t errlen)
{
	size_t cap = MVOD_LCM_LOG_HEADER + max_event;
	struct mvod_lcm_log *log = calloc(1, sizeof(*log) + cap);
	if (!log)
		return -ENOMEM;
	log->cap = cap;
	int ret = mvod_output_open(what, path, &log->out, err, errlen);
	if (ret) {
		free(log);
		return ret;
	}
	*out = log;
	return 0;
}

static uint8_t *put_be(uint8_t *p, uint64_t v, int bytes)
{
	for (int i = bytes - 1; i >= 0; i--, v >>= 8)
		p[i] = (uint8_t)v;
	return p + bytes;
}

/* The receive time LCM's logger stamps: wall clock, microseconds. */
static int64_t now_us(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_REALTIME, &ts);
	return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

int mvod_lcm_log_write(struct mvod_lcm_log *log, const char *channel, const void *data, size_t len)
{
	return mvod_lcm_log_write_at(log, channel, data, len, now_us());
}

int mvod_lcm_log_write_at(struct mvod_lcm_log *log, const char *channel, const void *data,
			  size_t len, int64_t utime)
{
	if (log->error)
		return log->error;
	size_t clen = strlen(channel);
	if (MVOD_LCM_LOG_HEADER + clen + len > log->cap)
		return -EMSGSIZE;
	uint8_t *p = put_be(log->buf, LOG_SYNC, 4);
	p = put_be(p, (uint64_t)log->next_event, 8);
	p = put_be(p, (uint64_t)utime, 8);
	p = put_be(p, clen, 4);
	p = put_be(p, len, 4);
	memcpy(p, channel, clen);
	memcpy(p + clen, data, len);
	log->error = mvod_output_write(log->out, log->buf, MVOD_LCM_LOG_HEADER + clen + len);
	log->next_event += !log->error;
	return log->error;
}

int mvod_lcm_log_reopen(struct mvod_lcm_log *log, char *err, size_t errlen)
{
	return mvod_output_reopen(log->out, err, errlen);
}

int mvod_lcm_log_close(struct mvod_lcm_log *log)
{
	if (!log)
		return 0;
	int ret = mvod_output_close(log->out);
	free(log);
	return ret;
}
