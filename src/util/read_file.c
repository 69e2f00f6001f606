#include "util/read_file.h"

#include <errno.h>
#include <stdlib.h>

#include "util/errbuf.h"
#include "util/input.h"

/* The buffer doubles from a page up to max + 1 bytes, the first byte too many. */
static int grow(char **buf, size_t *cap, size_t max)
{
	size_t want = *cap ? 2 * *cap : 4096;
	size_t next = want > max + 1 ? max + 1 : want;
	char *b = realloc(*buf, next + 1);
	if (!b)
		return -ENOMEM;
	*buf = b;
	*cap = next;
	return 0;
}

int mvod_read_file(const char *path, size_t max, const char *what, int flags, char **out,
		   size_t *len, char *err, size_t errlen)
{
	struct mvod_input in;
	int ret = mvod_input_open(&in, path, what, flags, max, err, errlen);
	if (ret)
		return ret;
	char *buf = NULL;
	size_t n = 0, cap = 0;
	for (;;) {
		if (n == cap && (ret = grow(&buf, &cap, max)) != 0) {
			mvod_errf(err, errlen, ret, "cannot read %s: out of memory", path);
			break;
		}
		ssize_t r = mvod_input_read(&in, buf + n, cap - n, err, errlen);
		if (r <= 0) {
			ret = (int)r;
			break;
		}
		n += (size_t)r;
	}
	mvod_input_close(&in);
	if (ret) {
		free(buf);
		return ret;
	}
	buf[n] = '\0';
	*out = buf;
	if (len)
		*len = n;
	return 0;
}
