#!/usr/bin/python3
"""A three-window cockpit: starts one daemon per window (front, left, right) with the same
scene and seed in lockstep, drives them all with the same weather and ticks, checks that
every window reports the same world hash, and saves one frame per window.

    ./deploy/cockpit/drive.py [--binary build/nephele] [--ticks 120] [--out cockpit-frames]
"""
import argparse
import json
import os
import signal
import socket
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


class Window:
    def __init__(self, binary, name):
        self.name = name
        self.proc = subprocess.Popen([binary, "serve", "-c", os.path.join(HERE, name + ".toml")],
                                     stdout=subprocess.PIPE, text=True)
        ready = self.proc.stdout.readline()
        if not ready.startswith("nephele ready"):
            sys.exit(f"{name}: the daemon did not start")
        port = int(ready.split("socket=")[1].split()[0])
        self.sock = socket.create_connection(("127.0.0.1", port))
        self.file = self.sock.makefile("rb")

    def request(self, **fields):
        self.sock.sendall((json.dumps(fields) + "\n").encode())
        header = json.loads(self.file.readline())
        if not header["ok"]:
            sys.exit(f"{self.name}: {header['error']['message']}")
        image = header["result"].get("image")
        return header["result"], self.file.read(image["bytes"]) if image else None

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default="build/nephele")
    parser.add_argument("--ticks", type=int, default=120)
    parser.add_argument("--out", default="cockpit-frames")
    args = parser.parse_args()
    windows = [Window(args.binary, name) for name in ("front", "left", "right")]
    try:
        for w in windows:  # the same commands, in the same order, to every window
            w.request(cmd="set_weather", layer=1, type=9, base=900, thickness=400, coverage=50,
                      wind=[6, 2])
        for tick in range(1, args.ticks + 1):
            for w in windows:
                w.request(cmd="tick", dt=1 / 60)
            if tick % 30 == 0:
                hashes = {w.name: w.request(cmd="hash")[0]["hash"] for w in windows}
                same = len(set(hashes.values())) == 1
                print(f"tick {tick:4d}: " + "  ".join(f"{n} {h}" for n, h in hashes.items()) +
                      ("  (agree)" if same else "  DIFFER"))
                if not same:
                    sys.exit(1)
        os.makedirs(args.out, exist_ok=True)
        for w in windows:
            _, png = w.request(cmd="render", view=w.name)
            with open(os.path.join(args.out, w.name + ".png"), "wb") as f:
                f.write(png)
        print(f"frames written to {args.out}/")
    finally:
        for w in windows:
            w.stop()


if __name__ == "__main__":
    main()
