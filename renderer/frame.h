#pragma once
// A rendered frame: named channels, each computed only when asked for, and the camera and
// clock it was rendered from (docs/DATASETS.md, "Channels").
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "image/image.h"
#include "world/camera.h"
#include "world/infrared.h"

namespace nephele {

enum class Channel : std::uint8_t {
  kColour,      // linear RGB (sRGB when encoded to 8 bits)
  kCoverage,    // cloud opacity 1 - prod(1 - alpha): clouds only, never targets or ground
  kDepth,       // metres along the ray to the first opaque surface (ground, target); inf: sky
  kCloudDepth,  // metres along the ray where cloud opacity, front to back, first reaches 1/2
  kObjectId,    // 1 + the index of the target covering the pixel, clouds ignored; 0: none;
                // kSeaObjectId: the sea
  kVisibility,  // transmittance of the clouds in front of the first opaque surface
  kLwir,        // long-wave infrared band radiance, W m^-2 sr^-1 (world/infrared.h)
  kGlint,       // the sun's glint on the sea as seen (luminance, colour's units); 0 elsewhere
};

// The object id of the sea's pixels (a class of its own: neither sky nor a target).
inline constexpr float kSeaObjectId = -1.0f;

struct ChannelInfo {
  Channel channel;
  const char* name;  // as the CLI, the protocol and EXR layers spell it
};
inline constexpr std::array<ChannelInfo, 8> kChannels{{
    {Channel::kColour, "colour"},
    {Channel::kCoverage, "coverage"},
    {Channel::kDepth, "depth"},
    {Channel::kCloudDepth, "cloud_depth"},
    {Channel::kObjectId, "object_id"},
    {Channel::kVisibility, "visibility"},
    {Channel::kLwir, "lwir"},
    {Channel::kGlint, "glint"},
}};

inline const char* channelName(Channel c) {
  return kChannels[std::size_t(c)].name;
}
inline std::optional<Channel> channelFromName(std::string_view name) {
  for (const ChannelInfo& info : kChannels)
    if (name == info.name) return info.channel;
  return std::nullopt;
}
// The channels' names, or only the float planes' (every channel but colour and coverage).
inline std::string channelNames(bool planes_only = false) {
  std::string out;
  for (const ChannelInfo& info : kChannels) {
    if (planes_only && (info.channel == Channel::kColour || info.channel == Channel::kCoverage))
      continue;
    out += (out.empty() ? "" : ", ") + std::string(info.name);
  }
  return out;
}

// A set of channels.
class ChannelSet {
 public:
  ChannelSet() = default;
  ChannelSet(std::initializer_list<Channel> channels) {
    for (Channel c : channels) add(c);
  }
  static ChannelSet all() { return ChannelSet((1u << kChannels.size()) - 1); }
  void add(Channel c) { bits_ |= 1u << unsigned(c); }
  bool has(Channel c) const { return bits_ & (1u << unsigned(c)); }
  bool empty() const { return bits_ == 0; }
  bool operator==(const ChannelSet&) const = default;

 private:
  explicit ChannelSet(unsigned bits) : bits_(bits) {}
  unsigned bits_ = 0;
};

// The pixels a view asks for: which channels, in what order, and how each is stored. The
// socket protocol's render and subscribe requests, the view's default, the render command's
// file and the dataset's files each name one.
struct Channels {
  enum class Pixels {
    kSrgb8,   // colour as sRGB R, G, B then coverage as A, 8 bits each, whatever the order
    kLinear,  // the same as linear floats (EXR: half unless EncodeOptions say otherwise)
    kPlanes,  // one float plane per channel in `order` (colour as R, G, B), then the `derived`
              // planes, with the frame's pose and clock where the format holds them (EXR
              // attributes)
    kGrey8,   // the one plane of `order` and `derived` as grey, grey_lo black to grey_hi white
              // linearly, in 8-bit R = G = B (the layout of every 8-bit colour image)
    kGrey16,  // the one plane, integers 0..65535 (ids, masks), as 16-bit grey (PNG)
  };
  Channels() = default;
  Channels(std::vector<Channel> channels, Pixels as = Pixels::kSrgb8,
           std::vector<std::string> derived_planes = {})
      : order(std::move(channels)), pixels(as), derived(std::move(derived_planes)) {}

  std::vector<Channel> order;
  Pixels pixels = Pixels::kSrgb8;
  std::vector<std::string> derived;     // names of the frame's derived planes (Frame::derived)
  double grey_lo = 0.0, grey_hi = 1.0;  // kGrey8's display range, in the plane's units

  bool has(Channel c) const { return std::find(order.begin(), order.end(), c) != order.end(); }
  ChannelSet set() const {
    ChannelSet out;
    for (Channel c : order) out.add(c);
    return out;
  }
  bool operator==(const Channels&) const = default;
  // Every channel of `set`, in the order of kChannels, as float planes.
  static Channels planesOf(const ChannelSet& set) {
    Channels out{{}, Pixels::kPlanes};
    for (const ChannelInfo& info : kChannels)
      if (set.has(info.channel)) out.order.push_back(info.channel);
    return out;
  }
};

// Whether a frame needs the GL renderer's target layers besides its colour target (what
// Renderer::reserve is asked for): the scene has targets, or depth or object ids are asked.
inline bool needsTargetLayers(bool scene_has_targets, const ChannelSet& channels) {
  return scene_has_targets || channels.has(Channel::kDepth) || channels.has(Channel::kObjectId);
}

// Where a frame was seen from: the pose, the pinhole intrinsics and the clock.
struct FrameInfo {
  glm::dvec3 position{0.0};
  Orientation orientation;
  double vfov_deg = 60.0;
  int width = 0, height = 0;
  // Pinhole intrinsics in pixels, origin at the top-left corner of the top-left pixel, x right,
  // y down: a point at camera coordinates (right, down, forward) = (X, Y, Z) images at
  // (fx X / Z + cx, fy Y / Z + cy). Square pixels: fx = fy.
  double focal_px = 0.0;
  double cx = 0.0, cy = 0.0;
  double time_s = 0.0;
  std::uint64_t tick = 0;
};

inline FrameInfo frameInfo(const Camera& camera, double time_s, std::uint64_t tick = 0) {
  FrameInfo info;
  info.position = camera.position;
  info.orientation = camera.orientation;
  info.vfov_deg = camera.vfov_deg;
  info.width = camera.width;
  info.height = camera.height;
  info.focal_px = 0.5 * camera.height / std::tan(0.5 * glm::radians(camera.vfov_deg));
  info.cx = 0.5 * camera.width;
  info.cy = 0.5 * camera.height;
  info.time_s = time_s;
  info.tick = tick;
  return info;
}

// A float plane its user derives from a frame's channels (the dataset's brightness
// temperature and masks), named as an EXR layer: encode takes it as it takes a channel's.
struct DerivedPlane {
  std::string name;
  std::vector<float> values;  // one per pixel, rows top-down
};

// One frame. Rows run top to bottom; planes hold one float per pixel and are empty unless
// their channel was asked for.
struct Frame {
  FrameInfo info;
  ChannelSet channels;
  FloatImage colour;  // RGB and coverage as alpha: present for colour or coverage
  // Colour and coverage as the GL back end reads its 8-bit target (Renderer::renderSrgb8),
  // in place of `colour`: encoded as they are, never from floats.
  Srgb8Image srgb;
  std::vector<float> depth, cloud_depth, object_id, visibility, lwir, glint;
  std::vector<DerivedPlane> derived;

  int width() const { return info.width; }
  // visibility = 1 - coverage, from colour's alpha (both back ends composite it there).
  void visibilityFromCoverage() {
    visibility.resize(colour.rgba.size() / 4);
    for (std::size_t i = 0; i < visibility.size(); ++i)
      visibility[i] = 1.0f - colour.rgba[i * 4 + 3];
  }
  int height() const { return info.height; }
  // The w x h rectangle at (x0, y0) of every plane (an off-axis view cut from a centred
  // render); the intrinsics are the caller's to set.
  Frame cropped(int x0, int y0, int w, int h) const {
    Frame out;
    out.info = info;
    out.info.width = w;
    out.info.height = h;
    out.channels = channels;
    if (!colour.rgba.empty()) out.colour = cropImage(colour, x0, y0, w, h);
    if (!srgb.rgba.empty()) out.srgb = cropImage(srgb, x0, y0, w, h);
    for (const ChannelInfo& c : kChannels)
      if (const std::vector<float>* plane = ownPlane(c.channel); plane && !plane->empty())
        *out.ownPlane(c.channel) = cropPlane(*plane, info.width, info.height, 1, x0, y0, w, h);
    for (const DerivedPlane& d : derived)
      out.derived.push_back(
          {d.name, cropPlane(d.values, info.width, info.height, 1, x0, y0, w, h)});
    return out;
  }
  // The frame's own one-float-per-pixel plane of a channel; null for colour and coverage,
  // which live in `colour` (RGB and alpha).
  const std::vector<float>* ownPlane(Channel c) const {
    switch (c) {
      case Channel::kDepth:
        return &depth;
      case Channel::kCloudDepth:
        return &cloud_depth;
      case Channel::kObjectId:
        return &object_id;
      case Channel::kVisibility:
        return &visibility;
      case Channel::kLwir:
        return &lwir;
      case Channel::kGlint:
        return &glint;
      case Channel::kColour:
      case Channel::kCoverage:
        break;
    }
    return nullptr;
  }
  std::vector<float>* ownPlane(Channel c) {
    return const_cast<std::vector<float>*>(std::as_const(*this).ownPlane(c));
  }
  // The derived plane of that name; null without one.
  const DerivedPlane* derivedPlane(std::string_view name) const {
    for (const DerivedPlane& d : derived)
      if (d.name == name) return &d;
    return nullptr;
  }
  // The single-float plane of a channel (coverage is copied out of colour's alpha); colour,
  // three floats per pixel, has none: read `colour`.
  std::vector<float> plane(Channel c) const {
    if (const std::vector<float>* own = ownPlane(c)) return *own;
    if (c != Channel::kCoverage) return {};
    std::vector<float> alpha(colour.rgba.size() / 4);
    for (std::size_t i = 0; i < alpha.size(); ++i) alpha[i] = colour.rgba[i * 4 + 3];
    return alpha;
  }
};

// What a render is asked for beyond the scene.
struct FrameRequest {
  FrameRequest() = default;
  FrameRequest(ChannelSet asked, std::uint64_t at_tick = 0) : channels(asked), tick(at_tick) {}
  ChannelSet channels{Channel::kColour, Channel::kCoverage};
  std::uint64_t tick = 0;
  InfraredModel infrared;  // for lwir
};

// Colour, coverage and visibility all come from the composited colour image.
inline bool compositeAsked(const ChannelSet& c) {
  return c.has(Channel::kColour) || c.has(Channel::kCoverage) || c.has(Channel::kVisibility);
}

// A frame with the request's channels and the camera's info, its planes not yet filled.
inline Frame frameFor(const Camera& camera, double time_s, const FrameRequest& request) {
  Frame frame;
  frame.info = frameInfo(camera, time_s, request.tick);
  frame.channels = request.channels;
  return frame;
}

}  // namespace nephele
