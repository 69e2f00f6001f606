/* The names of mvod/status.h's enums: status messages, logs, the option table. */
#include "mvod/status.h"

#include <stddef.h>

const char *mvod_run_state_name(enum mvod_run_state s)
{
	static const char *const names[] = {"STARTING", "INITIALIZING", "TRACKING",
					    "LOST",     "SOURCE_DOWN",  "STOPPING"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "UNKNOWN";
}

const char *const mvod_axes_names[] = {"camera", "ros", NULL};
const char *const mvod_clock_names[] = {"monotonic", "realtime", NULL};
