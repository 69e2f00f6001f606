#!/usr/bin/env python3
"""A Python subscriber to mvod: prints every pose on MVOD_POSE2 and every status on MVOD_STATUS2.

(mvod.pose2_t and status2_t; mvod publishes the older pose_t and status_t beside them on MVOD_POSE
and MVOD_STATUS, whose constants both use.)

  PYTHONPATH=$(pkg-config --variable=pythondir mvod-lcmtypes) \\
      python3 subscribe.py 'file:///tmp/run.lcmlog?mode=r&speed=0'  # a log of a run; ends with it
  ... python3 subscribe.py URL                 # beside a running mvod: the URL of its --lcm-url

Needs LCM's Python module (pip install lcm) and mvod's generated package (import mvod).
"""
import sys

import lcm
from mvod import pose2_t, pose_t, status2_t, status_t

STATE_NAMES = {getattr(pose_t, n): n[len("STATE_"):] for n in dir(pose_t) if n.startswith("STATE_")}
FAULT_BITS = sorted((getattr(status_t, n), n[len("FAULT_"):])
                    for n in dir(status_t) if n.startswith("FAULT_"))


def state_name(state):
    return STATE_NAMES.get(state, str(state))  # a number: a state newer than these bindings


def fault_names(faults):
    """Fault bits as names joined by '|', bits newer than these bindings in hex; 'none' for 0."""
    names = [name for bit, name in FAULT_BITS if faults & bit]
    unknown = faults & ~sum(bit for bit, _ in FAULT_BITS)
    if unknown:
        names.append("0x%x" % (unknown & 0xFFFFFFFF))
    return "|".join(names) or "none"


def on_pose(channel, data):
    p = pose2_t.decode(data)
    print("pose frame=%d utime=%d position=%.6f,%.6f,%.6f orientation=%.6f,%.6f,%.6f,%.6f state=%s"
          " quality=%.3f keyframe=%d"
          % ((p.frame, p.utime) + tuple(p.position) + tuple(p.orientation)
             + (state_name(p.state), p.quality, p.keyframe)), flush=True)


def on_status(channel, data):
    s = status2_t.decode(data)
    print("status utime=%d frames=%d state=%s faults=%s map_points=%d keyframes=%d scale=%.6g"
          " latency_ms=%.3f"
          % (s.utime, s.frames, state_name(s.state), fault_names(s.faults), s.map_points,
             s.keyframes, s.scale, s.latency_ms), flush=True)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: %s LCM_URL (mvod's --lcm-url, or a file:// log with ?mode=r&speed=0)"
                 % sys.argv[0])
    url = sys.argv[1]
    try:
        lc = lcm.LCM(url)
    except RuntimeError:
        sys.exit("%s: LCM cannot open %s" % (sys.argv[0], url))
    lc.subscribe("MVOD_POSE2", on_pose)
    lc.subscribe("MVOD_STATUS2", on_status)
    try:
        while True:
            lc.handle()
    except OSError:  # LCM's file provider reports the end of a log as an error
        sys.exit(0 if url.startswith("file://") else 1)
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
