#!/usr/bin/python3
"""A rosbag of endohaptics-ros-bridge -> the bridge's per-tick CSV log (its --log), so recorded
sessions feed endohaptics-identify, endohaptics-replay and endohaptics-force-report.

    bag_to_tick_log.py BAG OUT.csv [--topic /EW/tick_log]

Reads the tick-log topic (std_msgs/Float64MultiArray, one message per tick; the column names in
layout.dim[0].label, teleop::tick_log_columns) with Debian's python3-rosbag and writes one CSV row
per message, in the bag's order. Exit 0 with a summary line; non-zero naming what was wrong (no
such topic, columns that change, times that do not increase). docs/ros.md.
"""
import argparse
import sys

import rosbag


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("bag")
    parser.add_argument("out")
    parser.add_argument("--topic", default="/EW/tick_log")
    args = parser.parse_args()
    columns = None
    rows = 0
    last_time = None
    try:
        bag = rosbag.Bag(args.bag)
    except Exception as e:  # rosbag raises several kinds; say which file and why
        sys.exit(f"bag_to_tick_log: cannot read {args.bag}: {e}")
    with bag, open(args.out, "w") as out:
        for _, msg, _ in bag.read_messages(topics=[args.topic]):
            if not msg.layout.dim or not msg.layout.dim[0].label:
                sys.exit(f"bag_to_tick_log: {args.topic}: a message without column names")
            names = msg.layout.dim[0].label.split(",")
            if columns is None:
                columns = names
                out.write(",".join(columns) + "\n")
            elif names != columns:
                sys.exit(f"bag_to_tick_log: {args.topic}: the columns changed at row {rows + 1}")
            if len(msg.data) != len(columns):
                sys.exit(f"bag_to_tick_log: {args.topic}: row {rows + 1} has {len(msg.data)} "
                         f"values for {len(columns)} columns")
            t = msg.data[0]
            if last_time is not None and t <= last_time:
                sys.exit(f"bag_to_tick_log: {args.topic}: row {rows + 1}: time {t} not after "
                         f"{last_time}")
            last_time = t
            out.write(",".join(repr(float(x)) for x in msg.data) + "\n")
            rows += 1
    if columns is None:
        sys.exit(f"bag_to_tick_log: {args.bag} has no messages on {args.topic}")
    print(f"bag_to_tick_log: {rows} ticks, {len(columns)} columns from {args.topic} -> {args.out}")


if __name__ == "__main__":
    main()
