#!/usr/bin/python3
"""The daemon's live fuzz: random requests of every command, legal and broken, over several
connections at once, against a running `nephele serve`, with the invariants of
docs/RELIABILITY.md checked as it goes.

Nothing here lists the protocol by hand. The commands are those of protocol/commands.inc, and
each command's fields, their kinds and ranges are learnt from the daemon's own request reader
before the fuzz starts: a probe field draws "unknown field (allowed: ...)", a value of the wrong
kind draws "must be a number (allowed: LO to HI)", a word that is no choice draws "(allowed: a,
b, c)". A command or field added tomorrow is fuzzed tomorrow, and one whose errors do not say
what is allowed fails the schema check. Nested objects (a cloud, a target) are filled from the
repository's own scene files, then mutated.

Invariants:
  - one well-formed reply per request line, in order, with the request's id;
  - every reply within STALL_BOUND seconds (30 s: the daemon answers, never hangs); replies
    later than REPLY_BOUND (5 s on two cores) are counted and reported with the daemon's own
    account of where the time went (its event=slow_request and event=slow_frame lines). Both
    bounds scale by NEPHELE_TIME_FACTOR for sanitizer builds. Under llvmpipe the first draw of
    each new shader variant compiles for up to seconds on the world thread (docs/RELIABILITY.md,
    "Live fuzz"), which is why the 5 s bound is reported rather than asserted;
  - every ROUND_TRIP requests, a snapshot and a restore of the state then give back the same
    hash (the snapshot itself must succeed: whatever the daemon accepted, it can save);
  - at the end, a restart from the shutdown snapshot restores the same hash.

Run by daemon_test.AbuseTest (a short run in CI), or alone for a long one:
    NEPHELE_BINARY=build/nephele python3 tests/daemon/live_fuzz.py --seconds 600 --seed 5
"""
import argparse
import glob
import json
import os
import random
import re
import socket
import sys
import threading
import time
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import daemon_test  # noqa: E402  (the harness: its reader of replies and its Daemon)

PROBE = "zz_probe"
REPLY_BOUND = 5.0 * float(os.environ.get("NEPHELE_TIME_FACTOR", "1"))
STALL_BOUND = 30.0 * float(os.environ.get("NEPHELE_TIME_FACTOR", "1"))
ROUND_TRIP = 300  # requests between snapshot round trips
ROUND_TRIP_NAME = "fuzz-roundtrip"  # a snapshot name the fuzz itself never sends
ERROR_CODES = {"bad_json", "bad_field", "unknown_command", "too_large", "unauthorized", "busy",
               "not_found", "limit", "failed"}

UNKNOWN = re.compile(r"([\w.\[\]]*)" + PROBE + r": unknown (?:field|key) \(allowed(?: here)?: "
                     r"([^)]*)\)")
RANGE = re.compile(r"\(allowed: (?:each )?(-?[\d.]+(?:e[+-]?\d+)?) to (-?[\d.]+(?:e[+-]?\d+)?)")
CHOICES = re.compile(r"is not allowed \(allowed: ([^)]*)\)")
VECTOR = re.compile(r"must be an array of (\d) numbers")


def commands(source):
    """The commands of protocol/commands.inc, in order."""
    with open(os.path.join(source, "protocol", "commands.inc")) as f:
        return re.findall(r"^NEPHELE_COMMAND\((\w+),\s*\w+\)", f.read(), re.M)


def scene_examples(source):
    """Tables of the repository's scene files by key ([[cloud]], [[target]], ...), as JSON."""
    examples = {}
    for path in sorted(glob.glob(os.path.join(source, "config", "scenes", "*.toml"))):
        with open(path, "rb") as f:
            try:
                scene = tomllib.load(f)
            except tomllib.TOMLDecodeError:
                continue
        for key, value in scene.items():
            for table in value if isinstance(value, list) else [value]:
                if isinstance(table, dict) and "mesh" not in table:
                    examples.setdefault(key, []).append(table)
    return examples


class Connection:
    """One socket connection: newline JSON out, replies (and their image bytes) in."""

    def __init__(self, port):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=2 * STALL_BOUND)
        self.file = self.sock.makefile("rb")

    def send_line(self, line):
        self.sock.sendall(line)

    def reply(self):
        """The next reply, past any subscription events; a render of several views is one reply
        (its last part)."""
        while True:
            header, _ = daemon_test.read_message(self.file)
            if "event" in header:
                continue
            image = (header.get("result") or {}).get("image") or {}
            if "parts" in image and image.get("part", 0) + 1 < image["parts"]:
                continue
            return header

    def ask(self, request):
        self.send_line((json.dumps(request) + "\n").encode())
        return self.reply()

    def close(self):
        self.file.close()
        self.sock.close()


class Field:
    """What the reader told about one field: its kind, range, choices or children."""

    def __init__(self, name):
        self.name = name
        self.kind = "raw"
        self.lo = self.hi = None
        self.size = 0  # a vector's
        self.choices = []
        self.children = {}  # an object's fields
        self.required = False

    def describe(self):
        text = self.name + ("*" if self.required else "") + ":" + self.kind
        if self.lo is not None:
            text += f"[{self.lo:g},{self.hi:g}]"
        if self.choices:
            text += "{" + "|".join(self.choices) + "}"
        if self.children:
            text += "(" + ", ".join(f.describe() for f in self.children.values()) + ")"
        return text


def at(request, path, obj):
    """`request` with `obj` placed at `path` (a list of keys)."""
    out = dict(request)
    node = out
    for key in path[:-1]:
        node[key] = dict(node.get(key) or {})
        node = node[key]
    if path:
        node[path[-1]] = obj
        return out
    out.update(obj)
    return out


def message(reply):
    return "" if reply.get("ok") else reply["error"]["message"]


def concerns(text, dotted):
    """Whether an error message is about the field `dotted` (a.b.c)."""
    return re.search(r"(^|[\s:])" + re.escape(dotted) + r"(\[\d+\])?: ", text) is not None


class Schema:
    """Every command's fields, learnt by probing the daemon's reader."""

    FILLS = [lambda f: f.lo, lambda f: "front", lambda f: "fz0", lambda f: 1,
             lambda f: [0, 0], lambda f: [0, 0, 1000], lambda f: {}, lambda f: True]

    def __init__(self, conn, names, examples):
        self.conn = conn
        self.examples = examples
        self.fields = {}
        self.fixed = {}  # the required fields' values that pass, by command
        for cmd in names:
            self.fixed[cmd] = {}
            self.fields[cmd] = self.probe_object(cmd, [], self.fixed[cmd])

    def ask(self, cmd, path, obj):
        return message(self.conn.ask(at({"cmd": cmd, "id": 1}, path, obj)))

    def probe_object(self, cmd, path, fixed, depth=0):
        prefix = ".".join(path)
        tried = {}
        fields = {}
        for _ in range(40):
            text = self.ask(cmd, path, dict(fixed, **{PROBE: 0}))
            m = UNKNOWN.search(text)
            if m:
                for key in (k.strip() for k in m.group(2).split(",")):
                    if key and key not in ("cmd", "id", PROBE):
                        fields.setdefault(key, Field(key))
                break
            # A required field is missing or its fill is wrong: try the next fill.
            m = re.search(r"(?:^|[\s:])" + (re.escape(prefix) + r"\." if prefix else "") +
                          r"(\w+)(?:\[\d+\])?: ", text)
            if not m or m.group(1) == PROBE:
                break
            key = m.group(1)
            field = fields.setdefault(key, Field(key))
            field.required = True
            self.learn(field, text)
            k = tried.get(key, 0)
            example = self.examples.get(key)
            fills = ([lambda f: example[0]] if example else []) + self.FILLS
            if k >= len(fills):
                break
            tried[key] = k + 1
            value = fills[k](field)
            if value is None:
                continue
            fixed[key] = value
        for key, field in fields.items():
            probe = dict(fixed)
            probe[key] = "\u0001"  # no number, name, choice or object
            text = self.ask(cmd, path, probe)
            dotted = prefix + "." + key if prefix else key
            if concerns(text, dotted):
                self.learn(field, text)
            if field.kind == "object" and depth < 1 and key not in self.examples:
                child = dict(fixed.get(key) or {}) if isinstance(fixed.get(key), dict) else {}
                field.children = self.probe_object(cmd, path + [key], child, depth + 1)
        return fields

    @staticmethod
    def learn(field, text):
        tail = text.split(": ", 1)[-1]
        if "must be a number" in text or "is out of range" in text:
            field.kind = "number" if field.kind != "integer" else "integer"
        if "must be an integer" in text:
            field.kind = "integer"
        if "must be true or false" in text:
            field.kind = "boolean"
        if "is not a name" in text or "must be a string of 1 to 64" in text:
            field.kind = "name"
        if "must be an object" in text or "must be a table" in text:
            field.kind = "object"
        m = VECTOR.search(text)
        if m:
            field.kind, field.size = "vector", int(m.group(1))
        m = RANGE.search(tail)
        if m and field.kind in ("number", "integer", "vector", "raw"):
            field.lo, field.hi = float(m.group(1)), float(m.group(2))
            if field.kind == "raw":
                field.kind = "number"
        m = CHOICES.search(text)
        if m:
            field.kind = "choice"
            field.choices = [c.strip() for c in m.group(1).split(",") if c.strip()]

    def describe(self):
        return {cmd: [f.describe() for f in fields.values()] for cmd, fields in self.fields.items()}


EDGES = [2**53 + 1, -(2**53 + 1), 2**63, 2**64, -0.0, 5e-324, 1.7976931348623157e308, -1e308,
         "x", None, True, [], {}, [1, 2, 3]]
NAMES = ["a", "b", "c", "front", "left", "x" * 64, "x" * 65, ".a", "a b", "../etc", "dir", "fifo",
         "sparse", "junk"]
# Stream addresses stay on the loopback, or are malformed without a host name.
ADDRESSES = ["udp://127.0.0.1:{p}", "rtp://127.0.0.1:{p}", "srt://127.0.0.1:{p}",
             "udp://127.0.0.1", "udp://127.0.0.1:abc", "udp://127.0.0.1:-5", "rtp://127.0.0.1:0",
             "udp://127.0.0.1:99999", "udp://:5000", "tcp://127.0.0.1:5000", "", "udp://"]
EXTRA_EXAMPLES = {
    "channels": [["colour"], ["colour", "coverage"], ["depth"], ["object_id"], ["nonsense"]],
    "views": [["front"], ["front", "left"], ["left", "left"], []],
    "waves": [[{"id": 1, "height": 1.5, "wavelength": 80}], [{"id": 2, "enabled": False}],
              [{"id": i, "height": 0.5} for i in range(9)]],
    "utc": ["2026-06-21T12:00Z", "2099-12-31T23:59:59+14:00", "1900-01-01T00:00Z", "noon"],
    "velocity": [[5, 0], [0, 200], [150, 150], [-3, 2]],
    "wind": [[5, 0], [0, 200], [150, 150]],
    "frustum": [{"left": -30, "right": 20, "bottom": -10, "top": 15}, {"left": 10, "right": -10}],
    "camera": [{"position": [0, 0, 500], "heading": 30}, {"width": 33, "height": 17}],
}


class Generator:
    """Requests of every command from the learnt schema: mostly legal, with edge values."""

    def __init__(self, schema, rng, views, stream_ports):
        self.schema = schema
        self.rng = rng
        self.views = views
        self.ports = stream_ports
        self.examples = dict(EXTRA_EXAMPLES, **schema.examples)

    def number(self, field, integer=False):
        rng = self.rng
        lo = field.lo if field.lo is not None else -1e4
        hi = field.hi if field.hi is not None else 1e4
        r = rng.random()
        if r < 0.6:  # sensible: magnitudes spread over orders of magnitude within the range
            span = hi - lo
            x = lo + span * 10 ** rng.uniform(-6, 0) if span > 0 else lo
            if lo < 0 < hi and rng.random() < 0.5:  # about zero, either side
                x = rng.choice([-1, 1]) * min(hi, -lo) * 10 ** rng.uniform(-6, 0)
        elif r < 0.85:
            x = rng.choice([lo, hi, (lo + hi) / 2, rng.uniform(lo, hi)])
        else:
            return rng.choice(EDGES + [lo - 1, hi + 1, hi * 1.0000001])
        return int(round(x)) if integer else x

    def value(self, key, field):
        rng = self.rng
        if key in ("view",) and rng.random() < 0.8:
            return rng.choice(self.views)
        if key == "address":
            return rng.choice(ADDRESSES).format(p=rng.choice(self.ports))
        if key == "name" and rng.random() < 0.9:
            return rng.choice(NAMES)
        if key in ("subscription", "stream") and rng.random() < 0.8:
            return rng.randint(-1, 12)
        example = self.examples.get(key)
        if example and field.kind in ("raw", "object"):
            return self.mutate(json.loads(json.dumps(rng.choice(example))))
        kind = field.kind
        if kind == "number":
            return self.number(field)
        if kind == "integer":
            return self.number(field, integer=True)
        if kind == "boolean":
            return rng.choice([True, False, True, False, 0, "true"])
        if kind == "name":
            return rng.choice(NAMES)
        if kind == "choice":
            return rng.choice(field.choices + ["nonsense"]) if rng.random() < 0.95 else 7
        if kind == "vector":
            return [self.number(field) for _ in range(field.size if rng.random() < 0.95 else 2)]
        if kind == "object":
            return self.object(field.children)
        return rng.choice(EDGES)

    def mutate(self, value):
        """Now and then one numeric leaf of an example becomes an edge value."""
        if self.rng.random() < 0.7:
            return value
        leaves = []

        def walk(node):
            items = node.items() if isinstance(node, dict) else enumerate(node) \
                if isinstance(node, list) else []
            for k, v in items:
                if isinstance(v, (int, float)) and not isinstance(v, bool):
                    leaves.append((node, k))
                elif isinstance(v, (dict, list)):
                    walk(v)
        walk(value)
        if leaves:
            node, k = self.rng.choice(leaves)
            node[k] = self.rng.choice(EDGES + [node[k] * 1e6, -node[k], 0])
        return value

    def object(self, fields, fixed=None):
        out = {}
        for key, field in fields.items():
            if field.required or self.rng.random() < 0.4:
                out[key] = self.value(key, field)
        if fixed and self.rng.random() < 0.5:
            for key, value in fixed.items():
                out.setdefault(key, value)
        if self.rng.random() < 0.02:
            out["unknown_key"] = 1
        return out

    def request(self, cmd):
        r = {"cmd": cmd}
        if cmd == "snapshot" or cmd == "restore":  # never the round trip's own name
            r["name"] = self.rng.choice(NAMES)
            return r
        if cmd in self.schema.fields:  # else a command that does not exist
            r.update(self.object(self.schema.fields[cmd], self.schema.fixed[cmd]))
        return r

    def line(self, cmd, request_id):
        """A request line, and whether it is broken (answered without its id)."""
        r = self.request(cmd)
        r["id"] = request_id
        line = json.dumps(r)
        broken = self.rng.random() < 0.05
        if broken:  # truncation, garbage, BOM, NUL
            line = self.rng.choice([line[:self.rng.randint(1, max(1, len(line) - 1))],
                                    "\ufeff" + line, line + "\0", line + "}", "{" * 40, "[]"])
        return line.encode("utf-8", "replace") + b"\n", broken


class Failure(AssertionError):
    pass


def run(daemon_factory, source, seconds, seed=5, connections=3, log=print):
    """Fuzzes the daemon `daemon_factory()` starts for `seconds`; returns the figures. Raises
    Failure on a broken invariant."""
    rng = random.Random(seed)
    d = daemon_factory()
    names = commands(source)
    probe = Connection(d.port)
    schema = Schema(probe, names, scene_examples(source))
    unlearnt = [cmd for cmd, fields in schema.fields.items()
                if not fields and cmd not in ("hello", "list_targets", "stats", "hash")]
    if unlearnt:
        raise Failure("the reader did not name the fields of " + ", ".join(unlearnt))
    views = [v["name"] for v in probe.ask({"cmd": "get_view"})["result"]["views"]]
    ports = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2)]
    for s in ports:
        s.bind(("127.0.0.1", 0))
        s.setblocking(False)
    gen = Generator(schema, rng, views, [s.getsockname()[1] for s in ports])

    conns = [Connection(d.port) for _ in range(connections)]
    figures = {"requests": 0, "round_trips": 0, "max_reply_s": 0.0, "slowest": None,
               "over_5s": 0,
               "by_command": {}}
    lock = threading.Lock()
    failures = []
    deadline = time.monotonic() + seconds
    next_round_trip = ROUND_TRIP
    window = 8  # requests in flight per connection

    def pump(conn, k, count):
        try:
            pump_checked(conn, k, count)
        except Exception as e:  # a broken connection or reply: the fuzz's failure
            failures.append(f"connection {k}: {e!r}")

    def pump_checked(conn, k, count):
        """Sends `count` requests on `conn`, `window` in flight, and checks every reply."""
        pending = {}  # id: (command, sent at, whether the line was broken)
        sent = 0
        while sent < count or pending:
            while sent < count and len(pending) < window:
                cmd = rng.choice(names + ["nonsense"])
                rid = k * 10**9 + figures["requests"] + sent
                line, broken = gen.line(cmd, rid)
                conn.send_line(line)
                pending[rid] = (cmd, time.monotonic(), broken)
                sent += 1
            # Replies come as the work finishes (PROTOCOL.md): matched by id, and a reply
            # without a known id to the oldest broken line.
            header = conn.reply()
            rid = header.get("id")
            if rid not in pending:
                broken = [i for i, p in pending.items() if p[2]]
                if not broken:
                    failures.append(f"reply {str(header)[:300]} matches no request")
                    return
                rid = broken[0]
            cmd, t0, _ = pending.pop(rid)
            waited = time.monotonic() - t0
            with lock:
                stat = figures["by_command"].setdefault(cmd, [0, 0.0])
                stat[0] += 1
                stat[1] = max(stat[1], waited)
                if waited > figures["max_reply_s"]:
                    figures["max_reply_s"] = waited
                    figures["slowest"] = cmd
            if not isinstance(header.get("ok"), bool):
                failures.append(f"reply {str(header)[:300]} to request {rid} ({cmd})")
            elif not header["ok"] and header["error"].get("code") not in ERROR_CODES:
                failures.append(f"unknown error code in {header}")
            if waited > STALL_BOUND:
                failures.append(f"{cmd} answered after {waited:.1f} s")
            elif waited > REPLY_BOUND:
                with lock:
                    figures["over_5s"] += 1

    try:
        while time.monotonic() < deadline and not failures:
            batch = 30
            threads = [threading.Thread(target=pump, args=(c, k, batch))
                       for k, c in enumerate(conns)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            figures["requests"] += batch * len(conns)
            for s in ports:  # the streams' datagrams are read and dropped
                try:
                    while s.recv(65536):
                        pass
                except BlockingIOError:
                    pass
            if figures["requests"] >= next_round_trip:
                next_round_trip += ROUND_TRIP
                saved = probe.ask({"cmd": "snapshot", "name": ROUND_TRIP_NAME})
                if not saved["ok"]:
                    raise Failure(f"the snapshot of an accepted state failed: {saved}")
                back = probe.ask({"cmd": "restore", "name": ROUND_TRIP_NAME})
                if not back["ok"] or back["result"]["hash"] != saved["result"]["hash"]:
                    raise Failure(f"restore gave {back} for the snapshot {saved}")
                figures["round_trips"] += 1
        if failures:  # with the daemon's own account of its slowest requests
            slow = probe.ask({"cmd": "stats"}).get("result", {}).get("slow_requests", {})
            raise Failure("; ".join(failures[:5]) + "\nthe daemon's slowest of each second:\n" +
                          "\n".join(json.dumps(t) for t in slow.get("slowest_per_second", [])))
        if d.proc.poll() is not None:
            raise Failure("the daemon died")
        stats = probe.ask({"cmd": "stats"})["result"]
        figures["slow_requests"] = stats.get("slow_requests")
        figures["snapshot_failures"] = stats.get("snapshot_failures")
        figures["render_ms"] = stats.get("render_ms")
        log = d.log_text().splitlines()
        figures["slow_frames"] = [line.split(" warning ")[-1] for line in log
                                  if "event=slow_frame" in line][-5:]
        figures["slow_request_lines"] = sum("event=slow_request" in line for line in log)
        busy = stats.get("world_thread") or {}
        figures["world_thread"] = {k: f"{v['count']} in {v['total_ms'] / 1000:.1f} s, "
                                      f"longest {v['max_ms']:.0f} ms" for k, v in
                                   sorted(busy.items(), key=lambda kv: -kv[1]["total_ms"])[:10]}
        # The end: held still, saved at SIGTERM, and restored by the next start.
        paused = probe.ask({"cmd": "set_time", "paused": True})
        if not paused["ok"]:
            raise Failure(f"set_time paused: {paused}")
        before = probe.ask({"cmd": "hash"})["result"]["hash"]
    finally:
        for c in conns + [probe]:
            c.close()
        for s in ports:
            s.close()
    code = d.stop()
    if code != 0:
        raise Failure(f"SIGTERM: exit code {code}: " + d.log_text()[-2000:])
    d.start()
    after_conn = Connection(d.port)
    after = after_conn.ask({"cmd": "hash"})["result"]["hash"]
    after_conn.close()
    if after != before:
        raise Failure(f"restart from the shutdown snapshot: hash {after}, saved {before}")
    figures["schema"] = schema.describe()
    return d, figures


def main():
    import tempfile
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60)
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--connections", type=int, default=3)
    parser.add_argument("--schema", action="store_true", help="print what the probe learnt")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as work:
        t0 = time.monotonic()
        d, figures = run(lambda: daemon_test.Daemon(work, **daemon_test.LIVE_FUZZ_DAEMON),
                         daemon_test.SOURCE, args.seconds, args.seed, args.connections)
        elapsed = time.monotonic() - t0
        d.stop()
        schema = figures.pop("schema")
        if args.schema:
            print(json.dumps(schema, indent=1))
        figures["requests_per_second"] = round(figures["requests"] / elapsed, 1)
        print(json.dumps(figures, indent=1))
        with open(d.log_path) as f:
            slow = [line.rstrip() for line in f if "event=slow_request" in line]
        print(f"{len(slow)} slow_request log lines", *slow[:20], sep="\n")


if __name__ == "__main__":
    main()
