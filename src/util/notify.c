#include "util/notify.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdint.h>

#include <systemd/sd-daemon.h>

#include "util/clock.h"

/* Only the run loop's thread calls these: plain statics are enough. */
static double watchdog_s; /* 0: no watchdog */
static double last_ping = -1e9, last_status = -1e9;
static bool ready_sent;

void mvod_notify_init(void)
{
	uint64_t usec = 0;
	/* > 0 only when WATCHDOG_USEC is set and WATCHDOG_PID is unset or ours. */
	watchdog_s = sd_watchdog_enabled(0, &usec) > 0 ? (double)usec / 1e6 : 0;
}

void mvod_notify_ready(void)
{
	if (ready_sent)
		return;
	ready_sent = true;
	sd_notify(0, "READY=1");
}

void mvod_notify_watchdog(void)
{
	if (watchdog_s <= 0)
		return;
	/* systemd asks for a ping at least every half period; a third leaves room for a slow frame. */
	double now = mvod_now_s();
	if (now - last_ping < watchdog_s / 3)
		return;
	last_ping = now;
	sd_notify(0, "WATCHDOG=1");
}

void mvod_notify_status(bool force, const char *fmt, ...)
{
	double now = mvod_now_s();
	if (!force && now - last_status < 1.0)
		return;
	last_status = now;
	char msg[256] = "STATUS=";
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg + 7, sizeof(msg) - 7, fmt, ap);
	va_end(ap);
	sd_notify(0, msg);
}

void mvod_notify_stopping(void)
{
	sd_notify(0, "STOPPING=1");
}
