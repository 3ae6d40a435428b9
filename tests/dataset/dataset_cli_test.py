"""`nephele dataset` end to end: a bad description writes nothing; four shard processes and a
merge equal one process, file for file; a sample rendered alone equals the same sample of the
full run; a run killed part-way and resumed equals an uninterrupted one; the COCO file passes
the checks a pycocotools-style reader relies on.

Run by ctest with NEPHELE_BINARY and NEPHELE_SOURCE_DIR set."""
import filecmp
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

BINARY = os.environ["NEPHELE_BINARY"]
SOURCE = os.environ["NEPHELE_SOURCE_DIR"]

SPEC = """
[dataset]
seed = 5
samples = 8
width = 160
height = 120
masks = true
depth = true
coverage = true

[sky]
genera = ["stratocumulus", "altocumulus"]
layers = [1, 2]
coverage = [0.3, 0.7]
base = [600.0, 1500.0]
thickness = [300.0, 800.0]

[camera]
altitude = [200.0, 2500.0]
pitch = [0.0, 10.0]

[[target]]
name = "aircraft"
shape = "mesh"
mesh = "{mesh}"
count = [1, 2]
distance = [300.0, 3000.0]

[[target]]
name = "buoy"
shape = "ellipsoid"
size = [5.0, 5.0, 5.0]
count = [0, 1]
distance = [150.0, 1500.0]
"""


def run(*args, **kw):
    return subprocess.run([BINARY, "--log-level", "warn", "dataset", *args],
                          capture_output=True, text=True, timeout=600, **kw)


def tree(root):
    files = []
    for d, _, names in os.walk(root):
        for n in names:
            files.append(os.path.relpath(os.path.join(d, n), root))
    return sorted(files)


class DatasetCliTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="nephele_dataset_")
        cls.spec = os.path.join(cls.tmp, "spec.toml")
        with open(cls.spec, "w") as f:
            f.write(SPEC.format(mesh=os.path.join(SOURCE, "config/scenes/aircraft.obj")))
        cls.single = os.path.join(cls.tmp, "single")
        r = run(cls.spec, "-o", cls.single)
        assert r.returncode == 0, r.stderr

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def assertSameTree(self, a, b):
        self.assertEqual(tree(a), tree(b))
        for f in tree(a):
            self.assertTrue(filecmp.cmp(os.path.join(a, f), os.path.join(b, f), shallow=False), f)

    def test_bad_description_writes_nothing(self):
        bad = os.path.join(self.tmp, "bad.toml")
        with open(bad, "w") as f:
            f.write("[dataset]\nsamples = 3\n[sky]\ncoverage = [0.9, 0.1]\n")
        out = os.path.join(self.tmp, "bad_out")
        r = run(bad, "-o", out)
        self.assertEqual(r.returncode, 2)
        self.assertIn("bad.toml:4: sky.coverage: the low end 0.9 is above the high end 0.1",
                      r.stderr)
        self.assertFalse(os.path.exists(out))
        r = run(self.spec, "-o", out, "--shard", "4/4")
        self.assertEqual(r.returncode, 2)
        self.assertIn("--shard: '4/4' is not I/N", r.stderr)
        self.assertFalse(os.path.exists(out))

    def test_four_shards_and_a_merge_equal_one_run(self):
        out = os.path.join(self.tmp, "sharded")
        procs = [subprocess.Popen([BINARY, "--log-level", "warn", "dataset", self.spec, "-o", out,
                                   "--shards", "4"], env={**os.environ, "JOB_COMPLETION_INDEX": str(i)},
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE)
                 for i in range(4)]
        for p in procs:
            _, err = p.communicate(timeout=600)
            self.assertEqual(p.returncode, 0, err)
        self.assertFalse(os.path.exists(os.path.join(out, "annotations.json")))
        r = run(self.spec, "-o", out, "--merge")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertSameTree(self.single, out)

    def test_a_sample_regenerates_alone(self):
        out = os.path.join(self.tmp, "alone")
        r = run(self.spec, "-o", out, "--only", "5")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual([f for f in tree(out) if "000005" not in f], ["dataset.json"])
        for f in tree(out):
            self.assertTrue(filecmp.cmp(os.path.join(out, f), os.path.join(self.single, f),
                                        shallow=False), f)

    def test_killed_run_resumes_to_the_same_dataset(self):
        out = os.path.join(self.tmp, "resumed")
        p = subprocess.Popen([BINARY, "dataset", self.spec, "-o", out],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        records = os.path.join(out, "records")
        deadline = time.time() + 120
        while time.time() < deadline:
            if os.path.isdir(records) and len(os.listdir(records)) >= 2:
                break
            time.sleep(0.01)
        p.send_signal(signal.SIGKILL)
        p.wait()
        done = len([f for f in os.listdir(records) if f.endswith(".json")])
        self.assertLess(done, 8, "the run finished before it could be killed")
        r = run(self.spec, "-o", out, "--resume")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertSameTree(self.single, out)

    def test_coco_file_is_what_readers_expect(self):
        with open(os.path.join(self.single, "annotations.json")) as f:
            coco = json.load(f)
        for key in ("images", "annotations", "categories", "info", "licenses"):
            self.assertIn(key, coco)
        categories = {c["id"]: c["name"] for c in coco["categories"]}
        self.assertEqual(categories, {1: "aircraft", 2: "buoy"})
        images = {i["id"]: i for i in coco["images"]}
        self.assertEqual(len(images), 8)
        for i in images.values():
            self.assertEqual((i["width"], i["height"]), (160, 120))
            self.assertTrue(os.path.exists(os.path.join(self.single, i["file_name"])))
            self.assertIn("focal_px", i["camera"])
        ids = [a["id"] for a in coco["annotations"]]
        self.assertEqual(len(ids), len(set(ids)))
        self.assertGreater(len(ids), 4)
        for a in coco["annotations"]:
            self.assertIn(a["image_id"], images)
            self.assertIn(a["category_id"], categories)
            self.assertEqual(a["iscrowd"], 0)
            x, y, w, h = a["bbox"]
            self.assertTrue(0 <= x and 0 <= y and w > 0 and h > 0 and x + w <= 160 and y + h <= 120)
            seg = a["segmentation"]
            self.assertEqual(seg["size"], [120, 160])
            self.assertEqual(sum(seg["counts"]), 160 * 120)
            self.assertEqual(sum(seg["counts"][1::2]), a["area"])
            self.assertLessEqual(a["area"], a["area_full"])
            self.assertTrue(0.0 <= a["visibility"] <= 1.0)
        # YOLO lines: one per annotation, class index and a box inside the unit square.
        lines = 0
        for name in os.listdir(os.path.join(self.single, "labels")):
            for line in open(os.path.join(self.single, "labels", name)):
                c, *box = line.split()
                self.assertIn(int(c), (0, 1))
                self.assertTrue(all(0.0 <= float(v) <= 1.0 for v in box))
                lines += 1
        self.assertEqual(lines, len(ids))
        with open(os.path.join(self.single, "manifest.jsonl")) as f:
            manifest = [json.loads(line) for line in f]
        self.assertEqual([m["index"] for m in manifest], list(range(8)))
        self.assertTrue(all("layers" in m and "targets" in m and "seed" in m for m in manifest))


if __name__ == "__main__":
    unittest.main()
