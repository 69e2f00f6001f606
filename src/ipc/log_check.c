/*
 * The LCM event log format (lcm/eventlog.c, unchanged since LCM 1.0), big-endian, per event:
 *   uint32 sync 0xEDA1DA01, int64 event number, int64 time (us), int32 channel length,
 *   int32 data length, then the channel name and the data.
 */
#include "ipc/log_check.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/errbuf.h"
#include "util/input.h"

#define SYNC 0xEDA1DA01u
#define HEADER_BYTES 28
/* LCM's reader refuses channel names of 1000 bytes or more (lcm_eventlog_read_next_event). */
#define MAX_CHANNEL 999
/*
 * An event cut short at the end of the log is a stopped writer when its length is one LCM
 * can allocate without harm: mvod's messages are under 1 KiB, LCM's UDP limit is 256 KiB;
 * 64 MiB is generous for any image-carrying type. Beyond it the length is garbage.
 */
#define MAX_CUT_DATA (64 << 20)

static uint32_t be32(const uint8_t *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* Reads all of len bytes at off, retrying after signals; the count read, or -errno. */
static ssize_t read_at(int fd, uint8_t *buf, size_t len, off_t off)
{
	size_t got = 0;
	while (got < len) {
		ssize_t r = pread(fd, buf + got, len - got, off + (off_t)got);
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0)
			return -errno;
		if (r == 0)
			break;
		got += (size_t)r;
	}
	return (ssize_t)got;
}

/*
 * The event at off: its total length, or 0 with why filled (and *cut when it is only cut
 * short by the end of the file).
 */
static int64_t event_len(const uint8_t *h, int64_t off, int64_t size, bool *cut, char *why,
			 size_t whylen)
{
	int64_t left = size - off;
	/*
	 * LCM reads the 4 bytes after each event and drops the event unless they are a sync
	 * word (or fewer than 4 remain): only then does it read every event before this one.
	 */
	if (left < HEADER_BYTES) {
		*cut = left < 4 || be32(h) == SYNC;
		snprintf(why, whylen, "the log ends %lld bytes into an event header of %d",
			 (long long)left, HEADER_BYTES);
		return 0;
	}
	int32_t chan = (int32_t)be32(h + 20), data = (int32_t)be32(h + 24);
	if (be32(h) != SYNC)
		snprintf(why, whylen, "no event starts here (sync word 0x%08x, not 0x%08x)",
			 be32(h), SYNC);
	else if (chan < 1 || chan > MAX_CHANNEL)
		snprintf(why, whylen, "channel name length %d is not within 1..%d", chan,
			 MAX_CHANNEL);
	else if (data < 0)
		snprintf(why, whylen, "data length %d is negative", data);
	else if (HEADER_BYTES + (int64_t)chan + data > left) {
		*cut = data <= MAX_CUT_DATA;
		snprintf(why, whylen, "event of %lld bytes runs past the end of the log (%lld "
			 "bytes left)", (long long)HEADER_BYTES + chan + data, (long long)left);
	} else
		return HEADER_BYTES + (int64_t)chan + data;
	return 0;
}

int mvod_lcmlog_check(int fd, struct mvod_lcmlog_check *out)
{
	struct stat st;
	if (fstat(fd, &st) < 0)
		return -errno;
	*out = (struct mvod_lcmlog_check){.size = st.st_size, .bad_offset = -1};
	int64_t off = 0;
	while (off < out->size) {
		uint8_t h[HEADER_BYTES];
		ssize_t got = read_at(fd, h, sizeof(h), off);
		if (got < 0)
			return (int)got;
		/* The file may shrink while it is read: what was read is what it holds. */
		int64_t len = event_len(h, off, got < HEADER_BYTES ? off + got : out->size,
					&out->cut, out->why, sizeof(out->why));
		if (len == 0) {
			out->bad_offset = off;
			return 0;
		}
		off += len;
		out->events++;
	}
	return 0;
}

int mvod_lcmlog_vet(const char *path, struct mvod_lcmlog_check *out, char *err, size_t errlen)
{
	/* An input (no output of this run may be it), and a regular file: it is read by offset. */
	struct mvod_input in;
	int ret = mvod_input_open(&in, path, "LCM log", 0, SIZE_MAX, err, errlen);
	if (ret)
		return ret;
	ret = mvod_lcmlog_check(in.fd, out);
	mvod_input_close(&in);
	if (ret)
		return mvod_errf(err, errlen, ret, "cannot read log %s: %s", path, strerror(-ret));
	if (out->events == 0 && (out->bad_offset < 0 || out->cut))
		return mvod_errf(err, errlen, -ENODATA, "log %s holds no whole event (%lld bytes)",
				 path, (long long)out->size);
	if (out->bad_offset < 0 || out->cut)
		return 0;
	return mvod_errf(err, errlen, -EIO, "log %s is corrupt at byte %lld of %lld: %s; the "
			 "%lld events before it are intact (truncate -s %lld keeps only them)", path,
			 (long long)out->bad_offset, (long long)out->size, out->why,
			 (long long)out->events, (long long)out->bad_offset);
}
