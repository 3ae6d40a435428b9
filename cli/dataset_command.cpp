#include "cli/dataset_command.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <future>
#include <mutex>
#include <sstream>
#include <thread>

#include <unistd.h>

#include "cli/render_command.h"
#include "config/table_reader.h"
#include "dataset/dataset.h"
#include "dataset/dataset_file.h"
#include "renderer/renderer.h"
#include "world/counter_random.h"
#include "world/file_output.h"

namespace nephele {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::string sampleName(int index) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d", index);
  return name;
}

std::string writeText(const fs::path& path, const std::string& text) {
  return writeFileAtomically(path.string(),
                             {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()},
                             "dataset file");
}

// 64-bit FNV-1a of the description's text: a run resumed or sharded into a directory must
// come from the same description.
std::uint64_t textHash(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : text) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

// "I/N" or, with --shards N, I from the environment of a Kubernetes Indexed Job or a Slurm
// array task.
std::string shardOf(const DatasetCommandOptions& o, int& index, int& count) {
  index = 0, count = 1;
  if (!o.shard.empty()) {
    char slash = 0;
    std::istringstream in(o.shard);
    if (!(in >> index >> slash >> count) || slash != '/' || !in.eof() || count < 1 || index < 0 ||
        index >= count)
      return "--shard: '" + o.shard + "' is not I/N with 0 <= I < N";
    return "";
  }
  if (!o.shards) return "";
  count = *o.shards;
  for (const char* variable : {"JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"}) {
    const char* value = std::getenv(variable);
    if (!value) continue;
    char* end = nullptr;
    const long i = std::strtol(value, &end, 10);
    long base = 0;
    if (std::string(variable) == "SLURM_ARRAY_TASK_ID")
      if (const char* min = std::getenv("SLURM_ARRAY_TASK_MIN"))
        base = std::strtol(min, nullptr, 10);
    if (*value == 0 || *end != 0 || i - base < 0 || i - base >= count)
      return std::string("--shards ") + std::to_string(count) + ": " + variable + "='" + value +
             "' is not a shard index 0 to " + std::to_string(count - 1);
    index = int(i - base);
    return "";
  }
  return "--shards: neither JOB_COMPLETION_INDEX (Kubernetes Indexed Job) nor "
         "SLURM_ARRAY_TASK_ID (Slurm array) is set; use --shard I/N";
}

// A rendered sample on its way to the encoder thread.
struct Rendered {
  int index;
  SampleScene sample;
  Frame frame;
};

// The planes a sample's files show besides its channels (Frame::derived): brightness
// temperature in the infrared band, the instance mask and, at sea, the glint mask.
void deriveSamplePlanes(const DatasetSpec& spec, const BandTable& band, Frame& frame) {
  if (spec.band == Band::kLwir) {
    std::vector<float> kelvin(frame.lwir.size());
    for (std::size_t i = 0; i < kelvin.size(); ++i)
      kelvin[i] = float(band.temperature(frame.lwir[i]));
    frame.derived.push_back({"brightness_temperature", std::move(kelvin)});
  }
  if (spec.write_masks) frame.derived.push_back({"instance_mask", instanceMask(frame)});
  if (!frame.glint.empty())
    frame.derived.push_back({"glint_mask", glintMask(frame, spec.glint_threshold)});
}

// The image: colour, or brightness temperature shown linearly from display_k.lo (black) to
// .hi (white).
Channels sampleImage(const DatasetSpec& spec) {
  if (spec.band != Band::kLwir) return {{Channel::kColour}, Channels::Pixels::kSrgb8};
  Channels grey{{}, Channels::Pixels::kGrey8, {"brightness_temperature"}};
  grey.grey_lo = spec.display_k.lo;
  grey.grey_hi = spec.display_k.hi;
  return grey;
}

// The EXR's layers: radiance and brightness temperature in the infrared band, depths and ids,
// coverage and visibility as the description asks, and glint at sea; none (no EXR) unless
// the band or the description asks for one.
Channels sampleExr(const DatasetSpec& spec, const Frame& frame) {
  Channels exr{{}, Channels::Pixels::kPlanes};
  if (!(spec.write_depth || spec.write_coverage || spec.band == Band::kLwir)) return exr;
  if (spec.band == Band::kLwir) exr.order.push_back(Channel::kLwir);
  if (spec.write_depth)
    exr.order.insert(exr.order.end(), {Channel::kDepth, Channel::kCloudDepth, Channel::kObjectId});
  if (spec.write_coverage)
    exr.order.insert(exr.order.end(), {Channel::kCoverage, Channel::kVisibility});
  if (!frame.glint.empty()) exr.order.push_back(Channel::kGlint);
  if (spec.band == Band::kLwir) exr.derived.push_back("brightness_temperature");
  return exr;
}

// Labels, masks, images and the record of one sample; the record last, so that a sample
// whose record exists is complete (--resume). The frame gains the sample's derived planes.
std::string writeSample(const DatasetSpec& spec, const BandTable& band, const fs::path& dir,
                        Rendered& r, const EncodeOptions& encode) {
  const std::string name = sampleName(r.index);
  const int w = r.frame.width(), h = r.frame.height();
  const std::vector<TargetLabel> labels =
      labelTargets(r.frame, r.sample.target_class, spec.glint_threshold);
  deriveSamplePlanes(spec, band, r.frame);
  json record = r.sample.record;
  if (const DerivedPlane* glint = r.frame.derivedPlane("glint_mask")) {
    record["glint_fraction"] =
        double(std::count(glint->values.begin(), glint->values.end(), 65535.0f)) /
        double(glint->values.size());
    record["glint_file"] = "glint/" + name + ".png";
  }
  record["file_name"] = "images/" + name + ".png";
  record["labels"] = sampleLabelsJson(labels, w, h);
  const auto mask = [](const char* plane) {
    return Channels{{}, Channels::Pixels::kGrey16, {plane}};
  };
  std::string e =
      writeImage((dir / "images" / (name + ".png")).string(), r.frame, sampleImage(spec), encode);
  if (e.empty() && spec.write_masks)
    e = writeImage((dir / "masks" / (name + ".png")).string(), r.frame, mask("instance_mask"),
                   encode);
  if (e.empty() && r.frame.derivedPlane("glint_mask"))
    e = writeImage((dir / "glint" / (name + ".png")).string(), r.frame, mask("glint_mask"), encode);
  if (e.empty()) e = writeText(dir / "labels" / (name + ".txt"), yoloText(labels, w, h));
  if (const Channels exr = sampleExr(spec, r.frame);
      e.empty() && !(exr.order.empty() && exr.derived.empty())) {
    EncodeOptions zip = encode;
    zip.exr_compression = "zip";
    e = writeImage((dir / "exr" / (name + ".exr")).string(), r.frame, exr, zip);
  }
  if (e.empty()) e = writeText(dir / "records" / (name + ".json"), record.dump() + "\n");
  return e;
}

// Streams text into `path` through a temporary beside it, renamed into place when complete.
class StreamedFile {
 public:
  explicit StreamedFile(fs::path path) : path_(std::move(path)), out_(partial()) {}
  ~StreamedFile() {  // abandoned (an unreadable record): no temporary is left behind
    if (finished_) return;
    out_.close();
    std::error_code ec;
    fs::remove(partial(), ec);
  }
  std::ofstream& out() { return out_; }
  std::string finish() {
    finished_ = true;
    out_.close();
    std::error_code ec;
    if (!out_) return "cannot write '" + partial().string() + "'";
    fs::rename(partial(), path_, ec);
    return ec ? "cannot move '" + partial().string() + "' into place: " + ec.message() : "";
  }

 private:
  fs::path partial() const { return fs::path(path_.string() + ".partial"); }
  fs::path path_;
  std::ofstream out_;
  bool finished_ = false;
};

// annotations.json (COCO), manifest.jsonl and classes.txt from every sample's record, streamed
// record by record (two passes: annotations, then images), so that a merge of millions of
// samples holds one record at a time. The text equals one nlohmann::json dump of the whole.
std::string merge(const DatasetSpec& spec, const fs::path& dir) {
  int missing = 0, first_missing = -1;
  for (int i = 0; i < spec.samples; ++i)
    if (!fs::exists(dir / "records" / (sampleName(i) + ".json")) && missing++ == 0)
      first_missing = i;
  if (missing)
    return std::to_string(missing) + " of " + std::to_string(spec.samples) +
           " samples are not written yet (the first is " + std::to_string(first_missing) +
           "): run the missing shards, or this command with --resume";
  std::string error;
  auto read = [&](int i, json& record) {
    std::ifstream in(dir / "records" / (sampleName(i) + ".json"));
    try {
      in >> record;
      return true;
    } catch (const json::exception& e) {
      error = "records/" + sampleName(i) + ".json: " + e.what();
      return false;
    }
  };
  StreamedFile coco(dir / "annotations.json"), manifest(dir / "manifest.jsonl");
  std::ofstream& c = coco.out();
  c << "{\"annotations\":[";
  int next_id = 0;
  bool first = true;
  for (int i = 0; i < spec.samples; ++i) {
    json record;
    if (!read(i, record)) return error;
    for (const json& a : cocoAnnotations(record, next_id)) {
      c << (first ? "" : ",") << a.dump();
      first = false;
    }
    for (json& l : record["labels"]) l.erase("segmentation");  // in annotations.json
    manifest.out() << record.dump() << "\n";
  }
  c << "],\"categories\":" << cocoCategories(spec).dump() << ",\"images\":[";
  for (int i = 0; i < spec.samples; ++i) {
    json record;
    if (!read(i, record)) return error;
    c << (i ? "," : "") << cocoImage(spec, record).dump();
  }
  c << "],\"info\":" << cocoInfo(spec).dump() << ",\"licenses\":[]}\n";
  std::string classes;
  for (const TargetClass& t : spec.targets) classes += t.name + "\n";
  std::string e = coco.finish();
  if (e.empty()) e = manifest.finish();
  if (e.empty()) e = writeText(dir / "classes.txt", classes);
  return e;
}

// The description (read and parsed), this run's shard, and the --only indices checked: what
// is wrong with the request, or empty.
std::string readRequest(const DatasetCommandOptions& o, std::string& spec_text, DatasetSpec& spec,
                        int& shard, int& shards) {
  if (std::string e = config_detail::readTextFile(o.spec_path, "dataset description", spec_text);
      !e.empty() || !(e = parseDatasetText(spec_text, o.spec_path, spec)).empty())
    return e;
  if (std::string e = shardOf(o, shard, shards); !e.empty()) return e;
  for (int i : o.only)
    if (i < 0 || i >= spec.samples)
      return "--only: " + std::to_string(i) + " is not a sample index (allowed: 0 to " +
             std::to_string(spec.samples - 1) + ")";
  return "";
}

// Whether `dir` is new, or holds a dataset of the same description (its dataset.json's hash).
bool holdsThisDescription(const fs::path& dir, const json& header) {
  if (!fs::exists(dir / "dataset.json")) return true;
  std::ifstream in(dir / "dataset.json");
  json existing;
  try {
    in >> existing;
  } catch (const json::exception&) {
  }
  return existing.value("description_hash", "") == header["description_hash"];
}

// The directories the description's files go to, and dataset.json. Shards start together on
// shared storage: each writes the header under its own name and renames it into place (the
// same bytes whoever wins).
std::string prepareDirectory(const DatasetSpec& spec, const fs::path& dir, const json& header) {
  std::error_code ec;
  for (const char* sub : {"images", "masks", "glint", "labels", "exr", "records"}) {
    if ((std::string(sub) == "masks" && !spec.write_masks) ||
        (std::string(sub) == "glint" && !(spec.sea_probability > 0.0)) ||
        (std::string(sub) == "exr" && !spec.write_depth && !spec.write_coverage &&
         spec.band != Band::kLwir))
      continue;
    fs::create_directories(dir / sub, ec);
    if (ec) return "cannot create '" + (dir / sub).string() + "': " + ec.message();
  }
  const fs::path own = dir / ("dataset.json." + std::to_string(::getpid()));
  if (std::string e = writeText(own, header.dump(2) + "\n"); !e.empty()) return e;
  fs::rename(own, dir / "dataset.json", ec);
  if (ec) return "cannot write '" + (dir / "dataset.json").string() + "': " + ec.message();
  return "";
}

// The samples this run renders: --only's, else the shard's not yet written (--resume). A run
// killed while writing leaves files named *.partial, never a final name: these samples' are
// removed (other shards' may be in progress).
std::vector<int> samplesToRender(const DatasetCommandOptions& o, const DatasetSpec& spec,
                                 const fs::path& dir, int shard, int shards) {
  std::vector<int> todo;
  if (!o.only.empty()) {
    todo = o.only;
  } else {
    for (int i = shard; i < spec.samples; i += shards)
      if (!o.resume || !fs::exists(dir / "records" / (sampleName(i) + ".json"))) todo.push_back(i);
  }
  std::error_code ec;
  for (int i : todo)
    for (const char* file :
         {"images/%s.png", "masks/%s.png", "labels/%s.txt", "exr/%s.exr", "records/%s.json"}) {
      char name[64];
      std::snprintf(name, sizeof name, file, sampleName(i).c_str());
      fs::remove(dir / (std::string(name) + ".partial"), ec);
    }
  return todo;
}

// The next kDrawAhead samples' scenes, drawn on other threads while one renders: a sample
// whose heaps take longer to draw (60 to 106 ms, the first of a texture) than the one before
// takes to render (20 to 50 ms, layers only) is then drawn before it is needed. The first
// ones are drawn while the renderer starts.
class SampleDrawer {
 public:
  static constexpr std::size_t kDrawAhead = 2;
  SampleDrawer(const DatasetSpec& spec, const std::vector<int>& todo) : spec_(spec), todo_(todo) {
    for (std::size_t n = 0; n < todo_.size() && n < kDrawAhead; ++n) ahead_.push_back(draw(n));
  }
  // The n-th sample to render (taken in order) and the seconds its drawing took.
  std::pair<SampleScene, double> take(std::size_t n) {
    auto drawn = ahead_.front().get();
    ahead_.pop_front();
    if (n + kDrawAhead < todo_.size()) ahead_.push_back(draw(n + kDrawAhead));
    return drawn;
  }

 private:
  std::future<std::pair<SampleScene, double>> draw(std::size_t n) {
    return std::async(std::launch::async, [&spec = spec_, index = todo_[n]] {
      const auto t0 = Clock::now();
      SampleScene sample = drawSample(spec, index);
      return std::pair{std::move(sample), std::chrono::duration<double>(Clock::now() - t0).count()};
    });
  }
  const DatasetSpec& spec_;
  const std::vector<int>& todo_;
  std::deque<std::future<std::pair<SampleScene, double>>> ahead_;
};

// Labels and writes rendered samples on one worker thread while this one renders (it holds
// the GL context); at most two rendered samples wait.
class SampleWriter {
 public:
  SampleWriter(const DatasetSpec& spec, const fs::path& dir, const EncodeOptions& encode)
      : spec_(spec), band_(spec.infrared), dir_(dir), encode_(encode), worker_([this] { run(); }) {}
  ~SampleWriter() { finish(); }

  // Hands a sample to the worker once fewer than two wait; false (and the sample dropped)
  // once a write has failed.
  bool push(Rendered r) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.size() < 2 || !error_.empty(); });
    if (!error_.empty()) return false;
    queue_.push_back(std::move(r));
    changed_.notify_all();
    return true;
  }
  int written() {
    std::unique_lock lock(mutex_);
    return written_;
  }
  // Waits until every sample handed over is written: the first write's error, or empty.
  std::string finish() {
    {
      std::unique_lock lock(mutex_);
      done_ = true;
      changed_.notify_all();
    }
    if (worker_.joinable()) worker_.join();
    return error_;
  }
  double writeSeconds() const { return write_s_; }  // after finish

 private:
  void run() {
    for (;;) {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return !queue_.empty() || done_; });
      if (queue_.empty()) return;
      Rendered r = std::move(queue_.front());
      queue_.pop_front();
      changed_.notify_all();
      lock.unlock();
      const auto start = Clock::now();
      std::string e = writeSample(spec_, band_, dir_, r, encode_);
      lock.lock();
      write_s_ += std::chrono::duration<double>(Clock::now() - start).count();
      if (!e.empty() && error_.empty()) error_ = e;
      ++written_;
      changed_.notify_all();
    }
  }

  const DatasetSpec& spec_;
  const BandTable band_;
  const fs::path& dir_;
  const EncodeOptions& encode_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Rendered> queue_;
  bool done_ = false;
  std::string error_;
  int written_ = 0;
  double write_s_ = 0.0;
  std::jthread worker_;  // last: it starts once the members above are made
};

// The renderer the options ask for, sized for the description's samples; null with the error
// logged, and `code` the exit code.
std::unique_ptr<Renderer> datasetRenderer(const DatasetCommandOptions& o, const DatasetSpec& spec,
                                          int& code) {
  RendererOptions options;
  options.kind = o.renderer == "reference" ? RendererKind::kReference : RendererKind::kGl;
  options.gl_backend = backendFromName(o.gl_backend);
  options.render.channel_divisor = o.channel_divisor;
  options.render.heaps = spec.heaps;
  std::string error;
  std::unique_ptr<Renderer> renderer = createRenderer(options, error);
  if (!renderer) {
    spdlog::error("{}", error);
    code = 1;
    return nullptr;
  }
  if (std::string e = renderer->reserve(spec.width, spec.height, true, /*targets=*/true);
      !e.empty()) {
    spdlog::error("dataset.width/height: {}", e);
    code = 2;
    return nullptr;
  }
  spdlog::info("renderer: {}", renderer->description());
  return renderer;
}

// The channels a sample is rendered with: its band's, the labels', and what the description
// writes.
FrameRequest sampleRequest(const DatasetSpec& spec) {
  FrameRequest request;
  request.channels = {spec.band == Band::kLwir ? Channel::kLwir : Channel::kColour,
                      Channel::kObjectId, Channel::kVisibility};
  if (spec.write_depth)
    for (Channel c : {Channel::kDepth, Channel::kCloudDepth}) request.channels.add(c);
  if (spec.write_coverage) request.channels.add(Channel::kCoverage);
  if (spec.sea_probability > 0.0) request.channels.add(Channel::kGlint);
  return request;
}

// Draws, renders and writes the samples `todo`, the three overlapping on their own threads,
// with progress every 2 s: the exit code.
int renderSamples(const DatasetCommandOptions& o, const DatasetSpec& spec, const fs::path& dir,
                  const std::vector<int>& todo) {
  SampleDrawer drawer(spec, todo);
  int code = 0;
  const std::unique_ptr<Renderer> renderer = datasetRenderer(o, spec, code);
  if (!renderer) return code;
  FrameRequest request = sampleRequest(spec);
  SampleWriter writer(spec, dir, o.encode);
  double draw_s = 0.0, render_s = 0.0;
  const auto start = Clock::now();
  auto last_report = start;
  for (std::size_t n = 0; n < todo.size(); ++n) {
    const auto t0 = Clock::now();
    auto [sample, draw_seconds] = drawer.take(n);
    Rendered r{todo[n], std::move(sample), {}};
    const auto t1 = Clock::now();
    request.infrared = r.sample.infrared;
    r.frame = renderer->render(r.sample.scene, request);
    const auto t2 = Clock::now();
    spdlog::debug(
        "sample {}: drawn in {:.1f} ms (waited {:.1f} ms), rendered in {:.1f} ms: {}", r.index,
        1e3 * draw_seconds, std::chrono::duration<double, std::milli>(t1 - t0).count(),
        std::chrono::duration<double, std::milli>(t2 - t1).count(), renderer->statsLine());
    draw_s += draw_seconds;
    render_s += std::chrono::duration<double>(t2 - t1).count();
    if (!writer.push(std::move(r))) break;
    const double elapsed = std::chrono::duration<double>(t2 - start).count();
    if (std::chrono::duration<double>(t2 - last_report).count() >= 2.0) {
      last_report = t2;
      const int written = writer.written();
      const double rate = written / elapsed;
      spdlog::info("dataset: {}/{} samples, {:.1f} samples/s, {:.0f} s left", written, todo.size(),
                   rate, rate > 0 ? (todo.size() - written) / rate : 0.0);
    }
  }
  if (std::string e = writer.finish(); !e.empty()) {
    spdlog::error("{}", e);
    return 1;
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  auto perSample = [&](double seconds) { return todo.empty() ? 0.0 : 1e3 * seconds / todo.size(); };
  spdlog::info(
      "dataset: {} samples in {:.1f} s, {:.1f} samples/s (per sample: drawing {:.1f} ms, "
      "rendering {:.1f} ms, labelling and writing {:.1f} ms; the three overlap on their own "
      "threads)",
      todo.size(), elapsed, todo.empty() ? 0.0 : todo.size() / elapsed, perSample(draw_s),
      perSample(render_s), perSample(writer.writeSeconds()));
  return 0;
}

}  // namespace

void addDatasetCommand(CLI::App& app, DatasetCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "dataset", "Render a labelled cloud-clutter dataset (COCO, YOLO, masks; docs/DATASETS.md)");
  cmd->add_option("spec", o.spec_path, "Dataset description (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o.output_dir, "Output directory")->required();
  cmd->add_flag("--resume", o.resume, "Skip samples already written (their record exists)");
  cmd->add_option("--shard", o.shard, "Render only samples with index mod N = I, given as I/N");
  cmd->add_option("--shards", o.shards,
                  "N shards, this one's index from JOB_COMPLETION_INDEX (Kubernetes Indexed "
                  "Job) or SLURM_ARRAY_TASK_ID (Slurm array)")
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_flag("--merge", o.merge_only,
                "Only build annotations.json, manifest.jsonl and classes.txt from the records "
                "every shard wrote");
  cmd->add_option("--only", o.only, "Render only these sample indices (reproduce a sample)");
  cmd->add_option("--renderer", o.renderer, "gl, or the CPU reference (slow, exact)")
      ->check(CLI::IsMember({"gl", "reference"}))
      ->capture_default_str();
  cmd->add_option("--gl", o.gl_backend, "OpenGL back end")
      ->check(CLI::IsMember(kGlBackendNames))
      ->capture_default_str();
  cmd->add_option("--channel-divisor", o.channel_divisor,
                  "Cloud depth (depth = true): one traced ray per N x N pixels")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--png-compression", o.encode.png_compression, "PNG zlib level")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
}

int runDatasetCommand(const DatasetCommandOptions& o) {
  // Everything that can be wrong with the request is found before any file is written.
  // The text is read once: parsed here, and hashed to tie the output to it.
  std::string spec_text;
  DatasetSpec spec;
  int shard = 0, shards = 1;
  if (std::string e = readRequest(o, spec_text, spec, shard, shards); !e.empty()) {
    spdlog::error("{}", e);
    return 2;
  }
  const fs::path dir(o.output_dir);
  const json header = {{"description", o.spec_path},
                       {"description_hash", std::to_string(textHash(spec_text))},
                       {"samples", spec.samples},
                       {"width", spec.width},
                       {"height", spec.height}};
  if (!holdsThisDescription(dir, header)) {
    spdlog::error("{}: holds a dataset from another description; use an empty directory",
                  o.output_dir);
    return 2;
  }
  if (o.merge_only) {
    if (std::string e = merge(spec, dir); !e.empty()) {
      spdlog::error("{}", e);
      return 1;
    }
    spdlog::info("merged {} samples into {}/annotations.json", spec.samples, o.output_dir);
    return 0;
  }
  if (std::string e = prepareDirectory(spec, dir, header); !e.empty()) {
    spdlog::error("{}", e);
    return 1;
  }
  const std::vector<int> todo = samplesToRender(o, spec, dir, shard, shards);
  const int skipped =
      o.only.empty() ? (spec.samples - shard + shards - 1) / shards - int(todo.size()) : 0;
  spdlog::info(
      "dataset: {} samples to render{}{}", todo.size(),
      shards > 1 ? " (shard " + std::to_string(shard) + "/" + std::to_string(shards) + ")" : "",
      skipped > 0 ? ", " + std::to_string(skipped) + " already written" : "");
  if (const int code = renderSamples(o, spec, dir, todo); code != 0) return code;
  if (shards == 1 && o.only.empty()) {
    if (std::string e = merge(spec, dir); !e.empty()) {
      spdlog::error("{}", e);
      return 1;
    }
    spdlog::info("wrote {}/annotations.json, manifest.jsonl, classes.txt", o.output_dir);
  } else if (shards > 1) {
    spdlog::info("shard {}/{} done; when every shard is, run with --merge", shard, shards);
  }
  return 0;
}

}  // namespace nephele
