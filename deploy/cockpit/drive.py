#!/usr/bin/python3
"""A three-window cockpit: starts one daemon per window (front, left, right) with the same
scene and seed in lockstep, drives them all with the same weather and ticks, checks that
every window reports the same world hash, and saves one frame per window.

    ./deploy/cockpit/drive.py [--binary build/nephele] [--ticks 120] [--out cockpit-frames]

It uses the Python client, clients/python: this checkout's copy, installed or not.
"""
from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from typing import TypeVar

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "clients", "python"))
import nephele  # noqa: E402  (after the path to this checkout's client)

WINDOWS = ("front", "left", "right")
Result = TypeVar("Result")


class Window:
    """One window: its daemon, started from the window's config beside this script, and a
    client connected to it."""

    def __init__(self, binary: str, name: str) -> None:
        self.name = name
        try:
            self.daemon = nephele.LocalDaemon(os.path.join(HERE, name + ".toml"), binary)
        except (OSError, RuntimeError) as e:
            sys.exit(f"{name}: the daemon did not start ({e})")
        self.client = self.daemon.client()

    def stop(self) -> None:
        self.client.close()
        self.daemon.stop()


def on_every_window(windows: list[Window],
                    step: Callable[[Window], Result]) -> dict[str, Result]:
    """Runs `step` on every window in turn: the same commands, in the same order, to every
    window. A refusal stops the cockpit, naming the window."""
    results = {}
    for w in windows:
        try:
            results[w.name] = step(w)
        except nephele.NepheleError as e:
            sys.exit(f"{w.name}: {e.message}")
    return results


def drive(windows: list[Window], ticks: int, out: str) -> None:
    on_every_window(windows, lambda w: w.client.set_weather(layer=1, type=9, base=900,
                                                            thickness=400, coverage=50,
                                                            wind=[6, 2]))
    for tick in range(1, ticks + 1):
        on_every_window(windows, lambda w: w.client.tick(dt=1 / 60))
        if tick % 30 == 0:
            hashes = on_every_window(windows, lambda w: str(w.client.hash()["hash"]))
            same = len(set(hashes.values())) == 1
            print(f"tick {tick:4d}: " + "  ".join(f"{n} {h}" for n, h in hashes.items()) +
                  ("  (agree)" if same else "  DIFFER"))
            if not same:
                sys.exit(1)
    os.makedirs(out, exist_ok=True)
    pngs = on_every_window(windows, lambda w: w.client.render(w.name).data)
    for name, png in pngs.items():
        with open(os.path.join(out, name + ".png"), "wb") as f:
            f.write(png)
    print(f"frames written to {out}/")


def main() -> None:
    parser = argparse.ArgumentParser(description=" ".join((__doc__ or "").split("\n\n")[0].split()))
    parser.add_argument("--binary", default="build/nephele")
    parser.add_argument("--ticks", type=int, default=120)
    parser.add_argument("--out", default="cockpit-frames")
    args = parser.parse_args()
    windows: list[Window] = []
    try:
        for name in WINDOWS:
            windows.append(Window(args.binary, name))
        drive(windows, args.ticks, args.out)
    finally:
        for w in windows:
            w.stop()


if __name__ == "__main__":
    main()
