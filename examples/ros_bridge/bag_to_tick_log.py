#!/usr/bin/python3
"""A rosbag of endohaptics-ros-bridge -> the bridge's per-tick CSV log (its --log), so recorded
sessions feed endohaptics-identify, endohaptics-replay and endohaptics-force-report.

    bag_to_tick_log.py BAG OUT.csv [--topic /EW/tick_log]

Reads the tick-log topic (std_msgs/Float64MultiArray, one message per tick; the column names,
teleop::tick_log_columns, in layout.dim[0].label of one message a second) with Debian's
python3-rosbag and writes one CSV row per message, in the bag's order. Exit 0 with a summary line; non-zero naming what was wrong (no
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
    rows = []  # the data of every message; the names come with one message a second
    try:
        bag = rosbag.Bag(args.bag)
    except Exception as e:  # rosbag raises several kinds; say which file and why
        sys.exit(f"bag_to_tick_log: cannot read {args.bag}: {e}")
    with bag:
        for _, msg, _ in bag.read_messages(topics=[args.topic]):
            label = msg.layout.dim[0].label if msg.layout.dim else ""
            if label:
                names = label.split(",")
                if columns is None:
                    columns = names
                elif names != columns:
                    sys.exit(f"bag_to_tick_log: {args.topic}: the columns changed at row "
                             f"{len(rows) + 1}")
            rows.append(msg.data)
    if not rows:
        sys.exit(f"bag_to_tick_log: {args.bag} has no messages on {args.topic}")
    if columns is None:
        sys.exit(f"bag_to_tick_log: {args.topic}: no message names the columns (the bridge names "
                 "one a second: record at least 1 s)")
    last_time = None
    with open(args.out, "w") as out:
        out.write(",".join(columns) + "\n")
        for i, data in enumerate(rows, 1):
            if len(data) != len(columns):
                sys.exit(f"bag_to_tick_log: {args.topic}: row {i} has {len(data)} values for "
                         f"{len(columns)} columns")
            if last_time is not None and data[0] <= last_time:
                sys.exit(f"bag_to_tick_log: {args.topic}: row {i}: time {data[0]} not after "
                         f"{last_time}")
            last_time = data[0]
            out.write(",".join(repr(float(x)) for x in data) + "\n")
    print(f"bag_to_tick_log: {len(rows)} ticks, {len(columns)} columns from {args.topic} -> "
          f"{args.out}")

if __name__ == "__main__":
    main()
