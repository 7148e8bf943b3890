#!/usr/bin/env python3
"""An independent historian client for `mpmwatch serve` (docs/deploy.md, "How samples become rows").

Publishes the 2x2 loop of `config/default.toml` (controller `unit1`) the way a historian or DCS
gateway does: one message per tag, 100-1000 samples each, tags in a shuffled order every round,
one round of y2 held back and published after its next batch (a back-fill), a pause, and a few
bad messages. The model in the predictions leaves out ud1's effect on y1, so the one right alarm
is ud1->y1. Prints what it sent, what the monitor counted and the alarms it saw.

Reference only: the product and its tests never need Python.
    python3 -m venv v && v/bin/pip install eclipse-zenoh==1.10.2
    mpmwatch serve --config config/default.toml &
    v/bin/python scripts/historian_client.py --seed 1
"""

import argparse
import json
import random
import time
import urllib.request

import zenoh


def status(http):
    with urllib.request.urlopen(f"http://{http}/api/v1/controllers/unit1") as r:
        return json.load(r)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--endpoint", default="tcp/127.0.0.1:7447")
    ap.add_argument("--http", default="127.0.0.1:9464")
    args = ap.parse_args()
    rng = random.Random(args.seed)

    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("connect/endpoints", json.dumps([args.endpoint]))
    session = zenoh.open(conf)
    alarms = []
    session.declare_subscriber("mpm/unit1/alarm", lambda s: alarms.append(json.loads(s.payload.to_bytes())))
    time.sleep(1.0)

    def put(key, payload):
        session.put(key, payload, congestion_control=zenoh.CongestionControl.BLOCK)

    tags = ["mv/u1", "mv/u2", "dither/ud1", "dither/ud2", "cv/y1", "cv/y2", "pred/yhat1", "pred/yhat2"]
    t0 = float(int(time.time()) - 100_000)
    k, prev, sent, held = 0, [0.0, 0.0], 0, None
    for rnd in range(args.rounds):
        n = rng.randint(100, 1000)
        cols = {tag: ([], []) for tag in tags}
        for _ in range(n):
            ud = [rng.choice([-1.0, 1.0]), rng.choice([-1.0, 1.0])]
            noise = [rng.random() - 0.5, rng.random() - 0.5]
            y = [prev[0] + noise[0], 0.5 * prev[1] + noise[1]]
            yhat = [0.0, 0.5 * prev[1]]
            vals = [1.0 + ud[0], ud[1], ud[0], ud[1], y[0], y[1], yhat[0], yhat[1]]
            for tag, v in zip(tags, vals):
                cols[tag][0].append(t0 + k)
                cols[tag][1].append(v)
            prev, k = ud, k + 1
        order = tags[:]
        rng.shuffle(order)
        for tag in order:
            payload = json.dumps({"t": cols[tag][0], "v": cols[tag][1]})
            sent += n
            if rnd == 3 and tag == "cv/y2":
                held = (tag, payload)
                continue
            put(f"mpm/unit1/{tag}", payload)
        if rnd == 4 and held:
            time.sleep(2.0)
            put(f"mpm/unit1/{held[0]}", held[1])
        if rnd == 5:
            put("mpm/unit1/cv/y1", "not json")
            put("mpm/unit1/cv/nosuch", json.dumps({"t": [t0, t0 + 1], "v": [1, 2]}))
            put("mpm/unit1/cv/y1", json.dumps({"t": t0 + 10**6, "v": "NaN"}))
    print(f"sent {sent} good samples in {args.rounds} rounds ({k} rows), 3 bad messages")
    deadline = time.time() + 120
    while time.time() < deadline and not any(a["event"] == "raise" for a in alarms):
        time.sleep(1.0)
    st = status(args.http)
    print(json.dumps({key: st[key] for key in ["ingested", "dropped", "gap_rows", "backfilled_rows",
                                                "overflow_rows", "window_len", "window_contiguous",
                                                "last_run_status", "active_alarms"]}, indent=1))
    print("alarms seen:", [(a["event"], a["channel"], a.get("p_value")) for a in alarms])
    d = st["dropped"]
    print("all good samples ingested:", st["ingested"] == sent)
    # The held batch is back-filled only where it is still inside the window; older rows are
    # `late`. Bad messages: one not JSON (bad_payload, per message), two unknown-tag samples,
    # one NaN stamped far ahead (future).
    print("every good sample ingested or late:", st["ingested"] + d["late"] == sent)
    session.close()


if __name__ == "__main__":
    main()
