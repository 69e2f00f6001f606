// A C++ subscriber to mvod: prints every pose on MVOD_POSE2 and every status on MVOD_STATUS2
// (mvod::pose2_t and status2_t; mvod publishes the older pose_t and status_t beside them on
// MVOD_POSE and MVOD_STATUS, whose constants both use).
//
//   c++ subscribe.cpp $(pkg-config --cflags --libs mvod-lcmtypes) -o mvod-subscribe-cpp
//   ./mvod-subscribe-cpp 'file:///tmp/run.lcmlog?mode=r&speed=0'   # a log of a run; ends with it
//   ./mvod-subscribe-cpp URL                 # beside a running mvod: the URL of its --lcm-url
#include <cinttypes>
#include <cstdio>
#include <string>

#include <lcm/lcm-cpp.hpp>
#include <mvod/pose2_t.hpp>
#include <mvod/pose_t.hpp>
#include <mvod/status2_t.hpp>
#include <mvod/status_t.hpp>

using mvod::pose2_t;
using mvod::pose_t;
using mvod::status2_t;
using mvod::status_t;

static std::string state_name(int8_t state)
{
	switch (state) {
	case pose_t::STATE_STARTING: return "STARTING";
	case pose_t::STATE_INITIALIZING: return "INITIALIZING";
	case pose_t::STATE_TRACKING: return "TRACKING";
	case pose_t::STATE_LOST: return "LOST";
	case pose_t::STATE_SOURCE_DOWN: return "SOURCE_DOWN";
	case pose_t::STATE_STOPPING: return "STOPPING";
	}
	return std::to_string(state); // a state newer than these bindings
}

// Fault bits as names joined by '|', bits newer than these bindings in hex; "none" for 0.
static std::string fault_names(int32_t faults)
{
	static const struct { int32_t bit; const char *name; } names[] = {
		{status_t::FAULT_TRAJECTORY_WRITE, "TRAJECTORY_WRITE"},
		{status_t::FAULT_FRAME_UNREADABLE, "FRAME_UNREADABLE"},
		{status_t::FAULT_SOURCE_BROKEN, "SOURCE_BROKEN"},
		{status_t::FAULT_PUBLISH, "PUBLISH"},
	};
	std::string text;
	for (const auto &n : names)
		if (faults & n.bit) {
			text += (text.empty() ? "" : "|") + std::string(n.name);
			faults &= ~n.bit;
		}
	if (faults) {
		char hex[16];
		std::snprintf(hex, sizeof(hex), "0x%" PRIx32, static_cast<uint32_t>(faults));
		text += (text.empty() ? "" : "|") + std::string(hex);
	}
	return text.empty() ? "none" : text;
}

struct Printer {
	void pose(const lcm::ReceiveBuffer *, const std::string &, const pose2_t *p)
	{
		std::printf("pose frame=%" PRId64 " utime=%" PRId64 " position=%.6f,%.6f,%.6f "
			    "orientation=%.6f,%.6f,%.6f,%.6f state=%s quality=%.3f keyframe=%d\n",
			    p->frame, p->utime, p->position[0], p->position[1], p->position[2],
			    p->orientation[0], p->orientation[1], p->orientation[2],
			    p->orientation[3], state_name(p->state).c_str(), p->quality,
			    p->keyframe);
	}
	void status(const lcm::ReceiveBuffer *, const std::string &, const status2_t *s)
	{
		std::printf("status utime=%" PRId64 " frames=%" PRId64 " state=%s faults=%s "
			    "map_points=%" PRId32 " keyframes=%" PRId32 " scale=%.6g "
			    "latency_ms=%.3f\n", s->utime, s->frames, state_name(s->state).c_str(),
			    fault_names(s->faults).c_str(), s->map_points, s->keyframes, s->scale,
			    s->latency_ms);
	}
};

int main(int argc, char **argv)
{
	if (argc != 2) {
		std::fprintf(stderr, "usage: %s LCM_URL (mvod's --lcm-url, or a file:// log "
			     "with ?mode=r&speed=0)\n", argv[0]);
		return 2;
	}
	lcm::LCM lcm(argv[1]);
	if (!lcm.good()) {
		std::fprintf(stderr, "%s: LCM cannot open %s\n", argv[0], argv[1]);
		return 1;
	}
	std::setvbuf(stdout, nullptr, _IOLBF, 0); // a line per message, also into a pipe
	Printer printer;
	lcm.subscribe("MVOD_POSE2", &Printer::pose, &printer);
	lcm.subscribe("MVOD_STATUS2", &Printer::status, &printer);
	// LCM's file provider reports the end of a log as an error.
	while (lcm.handle() == 0)
		;
	return std::string(argv[1]).rfind("file://", 0) == 0 ? 0 : 1;
}
