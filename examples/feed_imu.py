#!/usr/bin/env python3
"""Feed a gyro CSV to stdout at its own sample times (or X times faster), one
line at a time, flushed: a stand-in for an IMU driver when measuring
`mmbm live` latency through a pipe. It sleeps until each sample's time
(no busy wait: it costs almost no CPU, so it does not take a core from the
process it feeds); a line leaves at most the system's sleep overshoot (about
0.1 ms on Linux) after its time.

    python3 examples/feed_imu.py walk.csv | mmbm live --policy threshold:0.4 --stats
"""
import sys
import time


def main() -> None:
    path = sys.argv[1]
    speed = float(sys.argv[2]) if len(sys.argv) > 2 else 1.0
    out = sys.stdout
    start = time.perf_counter()
    t0 = None
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                continue
            head = line.split(",", 1)[0]
            try:
                t = float(head)
            except ValueError:  # the header
                out.write(line)
                out.flush()
                continue
            if t0 is None:
                t0 = t
            due = start + (t - t0) / speed
            wait = due - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
            out.write(line)
            out.flush()


if __name__ == "__main__":
    main()
