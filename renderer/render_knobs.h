#pragma once
// The render knobs as one table (render_knobs.inc), one row a knob. From a row come the
// RenderSettings field and its default (render_settings.h), the scene file's [render] key and
// its check (config/scene_file.cpp), the `nephele render` flag (cli/render_command.cpp), the
// documentation (`nephele knobs`: README.md's [render] block, docs/ACCURACY.md's table) and
// the points `nephele bench` sweeps (cli/bench_command.cpp). Every value is held as a double:
// an integer exactly, a choice by its enum value, a boolean as 0 or 1.
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "world/limits.h"

namespace nephele {

struct RenderSettings;

enum class KnobType { kInteger, kNumber, kBoolean, kChoice };

// The values a knob allows. A number lies in `range`; with `listed` it is one of those, with
// `powers_of_two` a power of two. `zero` says what 0 does where 0 is allowed besides or inside
// the range ("0 for adaptive"); `unit` follows the values in messages and documents.
struct KnobValues {
  Range range{0.0, 0.0};
  std::vector<double> listed;
  bool powers_of_two = false;
  std::vector<std::string> names;  // a choice's names, in enum order
  std::string zero;
  std::string unit;

  KnobValues orZero(std::string what) const;
  KnobValues in(std::string unit_name) const;
};

KnobValues between(double lo, double hi);
KnobValues between(Range range);
KnobValues powersOfTwo(double lo, double hi);
KnobValues oneOf(std::vector<double> values);
KnobValues choices(std::vector<std::string> names);
KnobValues trueOrFalse();

// What a knob acts on: `nephele bench` sweeps it on the scenes that hold it, since a knob
// that cannot change a scene's image would only time the defaults again.
enum class KnobScope {
  kLayersOrClouds,  // sky planes, ellipsoid clouds or fields of heaps
  kLatticeLayers,   // sky planes with Gardner's lattice (neither rotated nor jittered)
  kLayers,          // sky planes
  kClouds,          // ellipsoid clouds or fields of heaps
  kSingleClouds,    // ellipsoid clouds where no field of thousands of heaps makes it seconds
  kFields,          // fields of heaps
  kShadowCasters,   // fields of heaps, or clouds that absorb light (light_extinction > 0)
  kPlanes,          // sky planes or weather layers
  kSea,             // the sea
  kAutomata,        // automaton clouds
  kAnything,        // every scene
};

// How `nephele bench` draws a point of a knob's sweep.
enum class KnobSweep {
  kSingle,     // a single render
  kMultipass,  // a single render with ellipsoid_passes = multipass, the only path it acts in
  kStream,     // a continuous view: the frame after flying into the view for 16 frames
  kModel,      // another model: its error against a reference with the same knob
  kReference,  // the CPU reference at this value, against the bench's reference, timed on the CPU
};

struct RenderKnob {
  std::string_view name;  // the scene file's key; the flag is --name with '-' for '_'
  KnobType type;
  KnobValues values;
  double default_value;
  std::vector<double> sweep;  // the values `nephele bench` draws besides the default
  KnobScope scope;
  KnobSweep how;
  std::string_view doc;  // one line: what it does
  double (*get)(const RenderSettings&);
  void (*set)(RenderSettings&, double);

  std::string flag() const;                // "--heap-shading-rate"
  std::string format(double value) const;  // as a scene file spells it: 4, 0.5, "fade", true
  std::string allowed() const;             // "1, 2 or 4 pixels between samples"
  std::string helpText() const;            // the flag's help: doc, allowed, default
};

// Every knob, in the table's order.
const std::vector<RenderKnob>& renderKnobs();
// The knob of that name, or null.
const RenderKnob* findRenderKnob(std::string_view name);

// The one check of a knob's value: "name: value is out of range (allowed: ...)" or "... is
// not allowed (allowed: ...)", or empty when `value` is allowed.
std::string knobError(const RenderKnob& knob, double value);
// Every knob of `settings` checked: the first error, or empty when all are allowed.
std::string validateRenderSettings(const RenderSettings& settings);
// A value as the command line writes it (a number, true or false, a choice's name) into
// `value`; the error names the knob and what is allowed. The value is not yet checked.
std::string parseKnobText(const RenderKnob& knob, std::string_view text, double& value);

// README.md's [render] block: every knob at its default with its doc as a comment.
std::string knobsToml();
// docs/ACCURACY.md's knob table: knob, default, allowed and swept values from the table, and
// each knob's measured columns ("turn it for | what it costs") from `measured`, by name.
std::string knobsMarkdown(const std::vector<std::pair<std::string, std::string>>& measured);
// The measured columns of the knob rows of a document holding knobsMarkdown's table.
std::vector<std::pair<std::string, std::string>> measuredKnobColumns(std::string_view document);

// A row's values as doubles: see the note at the top.
template <class T>
constexpr double knobValue(T v) {
  if constexpr (std::is_enum_v<T>)
    return double(int(v));
  else
    return double(v);
}
template <class T>
constexpr T fromKnobValue(double v) {
  if constexpr (std::is_enum_v<T>)
    return T(int(v));
  else if constexpr (std::is_same_v<T, bool>)
    return v != 0.0;
  else
    return T(v);
}
template <class T>
constexpr KnobType knobType() {
  if constexpr (std::is_enum_v<T>)
    return KnobType::kChoice;
  else if constexpr (std::is_same_v<T, bool>)
    return KnobType::kBoolean;
  else if constexpr (std::is_integral_v<T>)
    return KnobType::kInteger;
  else
    return KnobType::kNumber;
}
template <class... V>
std::vector<double> sweep(V... values) {
  return {knobValue(values)...};
}

}  // namespace nephele
