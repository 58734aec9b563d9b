"""Reads an MCAP log with Python's `mcap` package, its default reader
(`make_reader(f).iter_messages()`: seeking mode on a file), and prints the
messages per topic as JSON (tests/log_recovery.rs,
`a_killed_runs_log_reads_with_pythons_default_mcap_reader`; CI installs
`mcap` pinned in `.ci/run`).

    python3 mcap_read.py LOG.mcap
"""

import json
import sys

from mcap.reader import make_reader


def main():
    counts = {}
    with open(sys.argv[1], "rb") as f:
        for _schema, channel, _message in make_reader(f).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    print(json.dumps({"counts": counts}))


if __name__ == "__main__":
    main()
