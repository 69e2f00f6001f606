/*
 * Logging: one line per message on stderr, "mvod: LEVEL: text" in the foreground. Under
 * systemd, when stderr is the journal, lines carry sd-daemon's "<N>" priority prefix instead,
 * so journald records each line's priority.
 */
#ifndef MVOD_LOG_H
#define MVOD_LOG_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

enum mvod_log_level {
	MVOD_LOG_ERROR = 0,
	MVOD_LOG_WARN = 1,
	MVOD_LOG_INFO = 2,
	MVOD_LOG_DEBUG = 3,
};

void mvod_log_set_level(enum mvod_log_level level);
enum mvod_log_level mvod_log_get_level(void);
/* "error", "warn", "info", "debug" in enum order, NULL-terminated (the config file's choices). */
extern const char *const mvod_log_level_names[];
/*
 * Whether fd is the stream named by journal_stream (the JOURNAL_STREAM variable systemd sets:
 * "DEVICE:INODE" of the journal's socket). Decided for stderr at the first message.
 */
bool mvod_log_is_journal(const char *journal_stream, int fd);
/* Overrides that decision. */
void mvod_log_set_journal(bool journal);
void mvod_log(enum mvod_log_level level, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

#define LOG(level, ...) mvod_log(MVOD_LOG_##level, __VA_ARGS__)

#ifdef __cplusplus
}
#endif

#endif
