/*
 * systemd's service notifications (sd_notify(3)) for the Type=notify unit: readiness, watchdog
 * keep-alives, a status line and stopping. Outside systemd (no NOTIFY_SOCKET) every call is a
 * cheap no-op, so the run loop calls them unconditionally.
 */
#ifndef MVOD_NOTIFY_H
#define MVOD_NOTIFY_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Reads WATCHDOG_USEC/WATCHDOG_PID once; before it, the watchdog is off. */
void mvod_notify_init(void);
/* The source is open and the first frame is processed. Sent once. */
void mvod_notify_ready(void);
/* WATCHDOG=1 when a third of the watchdog period has passed since the last one. */
void mvod_notify_watchdog(void);
/* STATUS=line, at most once a second unless forced (a state change). */
void mvod_notify_status(bool force, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void mvod_notify_stopping(void);

#ifdef __cplusplus
}
#endif

#endif
