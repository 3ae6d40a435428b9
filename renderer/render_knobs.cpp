#include "renderer/render_knobs.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "renderer/render_settings.h"

namespace nephele {

KnobValues KnobValues::orZero(std::string what) const {
  KnobValues v = *this;
  v.zero = std::move(what);
  return v;
}

KnobValues KnobValues::in(std::string unit_name) const {
  KnobValues v = *this;
  v.unit = std::move(unit_name);
  return v;
}

KnobValues between(double lo, double hi) {
  return between(Range{lo, hi});
}

KnobValues between(Range range) {
  KnobValues v;
  v.range = range;
  return v;
}

KnobValues powersOfTwo(double lo, double hi) {
  KnobValues v = between(lo, hi);
  v.powers_of_two = true;
  return v;
}

KnobValues oneOf(std::vector<double> values) {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  KnobValues v = between(*lo, *hi);
  v.listed = std::move(values);
  return v;
}

KnobValues choices(std::vector<std::string> names) {
  KnobValues v = between(0.0, double(names.size()) - 1.0);
  v.names = std::move(names);
  return v;
}

KnobValues trueOrFalse() {
  return between(0.0, 1.0);
}

namespace {

// A number as documents and messages show it: integers in full, others as the stream does.
std::string shown(double v) {
  if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e15) {
    std::ostringstream out;
    out << static_cast<long long>(v);
    return out.str();
  }
  return formatNumber(v);
}

// "1, 2 or 4"
std::string listed(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i)
    out += (i == 0 ? "" : i + 1 == items.size() ? " or " : ", ") + items[i];
  return out;
}

bool powerOfTwo(double v) {
  return v >= 1.0 && v == std::floor(v) &&
         (static_cast<long long>(v) & (static_cast<long long>(v) - 1)) == 0;
}

}  // namespace

// The field behind each row, its default and accessors; see render_knobs.inc.
#define NEPHELE_KNOB(Type, field, default_value, name, allowed, points, scope, how, doc) \
  RenderKnob{name,                                                                       \
             knobType<Type>(),                                                           \
             allowed,                                                                    \
             knobValue(Type(default_value)),                                             \
             points,                                                                     \
             KnobScope::scope,                                                           \
             KnobSweep::how,                                                             \
             doc,                                                                        \
             [](const RenderSettings& s) { return knobValue(s.field); },                 \
             [](RenderSettings& s, double v) { s.field = fromKnobValue<Type>(v); }},
#define NEPHELE_HEAP_KNOB(Type, field, name, allowed, points, scope, how, doc) \
  RenderKnob{name,                                                             \
             knobType<Type>(),                                                 \
             allowed,                                                          \
             knobValue(HeapDrawing{}.field),                                   \
             points,                                                           \
             KnobScope::scope,                                                 \
             KnobSweep::how,                                                   \
             doc,                                                              \
             [](const RenderSettings& s) { return knobValue(s.heaps.field); }, \
             [](RenderSettings& s, double v) { s.heaps.field = fromKnobValue<Type>(v); }},

const std::vector<RenderKnob>& renderKnobs() {
  static const std::vector<RenderKnob> knobs{
#include "renderer/render_knobs.inc"
  };
  return knobs;
}

#undef NEPHELE_KNOB
#undef NEPHELE_HEAP_KNOB

const RenderKnob* findRenderKnob(std::string_view name) {
  for (const RenderKnob& knob : renderKnobs())
    if (knob.name == name) return &knob;
  return nullptr;
}

std::string RenderKnob::flag() const {
  std::string out = "--" + std::string(name);
  std::replace(out.begin(), out.end(), '_', '-');
  return out;
}

std::string RenderKnob::format(double value) const {
  switch (type) {
    case KnobType::kChoice: {
      const auto index = static_cast<std::size_t>(value);
      return value >= 0.0 && index < values.names.size() ? values.names[index] : shown(value);
    }
    case KnobType::kBoolean:
      return value != 0.0 ? "true" : "false";
    case KnobType::kInteger:
      return shown(value);
    case KnobType::kNumber:
      return formatNumber(value);
  }
  return "";
}

std::string RenderKnob::allowed() const {
  if (type == KnobType::kChoice) return listed(values.names);
  if (type == KnobType::kBoolean) return "true or false";
  std::string range;
  if (!values.listed.empty()) {
    std::vector<std::string> items;
    for (double v : values.listed) items.push_back(shown(v));
    range = listed(items);
  } else {
    range = (values.powers_of_two ? "a power of two from " : "") + shown(values.range.lo) + " to " +
            shown(values.range.hi);
  }
  if (!values.unit.empty()) range += " " + values.unit;
  if (values.zero.empty()) return range;
  return values.range.contains(0.0) ? range + "; " + values.zero : values.zero + ", or " + range;
}

std::string RenderKnob::helpText() const {
  return std::string(doc) + " (" + allowed() + "; default " + format(default_value) + ")";
}

std::string knobError(const RenderKnob& knob, double value) {
  const KnobValues& v = knob.values;
  const bool zero = !v.zero.empty() && value == 0.0;
  const bool whole = knob.type != KnobType::kNumber;
  if (!zero &&
      !(std::isfinite(value) && v.range.contains(value) && (!whole || value == std::floor(value))))
    return std::string(knob.name) + ": " + knob.format(value) +
           " is out of range (allowed: " + knob.allowed() + ")";
  const bool unlisted =
      !v.listed.empty() && std::find(v.listed.begin(), v.listed.end(), value) == v.listed.end();
  if (!zero && (unlisted || (v.powers_of_two && !powerOfTwo(value))))
    return std::string(knob.name) + ": " + knob.format(value) +
           " is not allowed (allowed: " + knob.allowed() + ")";
  return "";
}

std::string validateRenderSettings(const RenderSettings& settings) {
  for (const RenderKnob& knob : renderKnobs())
    if (std::string e = knobError(knob, knob.get(settings)); !e.empty()) return e;
  return "";
}

std::string parseKnobText(const RenderKnob& knob, std::string_view text, double& value) {
  const std::string s(text);
  const std::string error = std::string(knob.name) + ": '" + s + "' is not ";
  if (knob.type == KnobType::kChoice) {
    const auto& names = knob.values.names;
    const auto it = std::find(names.begin(), names.end(), s);
    if (it == names.end()) return error + "allowed (allowed: " + knob.allowed() + ")";
    value = double(it - names.begin());
    return "";
  }
  if (knob.type == KnobType::kBoolean) {
    if (s != "true" && s != "false") return error + "true or false";
    value = s == "true" ? 1.0 : 0.0;
    return "";
  }
  char* end = nullptr;
  errno = 0;
  if (knob.type == KnobType::kInteger) {
    const long long v = std::strtoll(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || errno == ERANGE || !heldExactly(v))
      return error + "an integer (allowed: " + knob.allowed() + ")";
    value = double(v);
    return "";
  }
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0') return error + "a number (allowed: " + knob.allowed() + ")";
  value = v;
  return "";
}

}  // namespace nephele

namespace nephele {
namespace {

// A default as TOML writes it: numbers of a `number` knob with a decimal point.
std::string tomlValue(const RenderKnob& knob, double v) {
  std::string s = knob.format(v);
  if (knob.type == KnobType::kChoice) return '"' + s + '"';
  if (knob.type == KnobType::kNumber && s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

// `text` as comments after `first` (at column 29), wrapped at 100 columns.
std::string commented(std::string first, std::string_view text) {
  constexpr std::size_t kColumn = 29, kWidth = 100;
  std::string out;
  std::string line =
      first.size() < kColumn ? first + std::string(kColumn - first.size(), ' ') : first + "  ";
  line += "#";
  std::istringstream words{std::string(text)};
  for (std::string word; words >> word;) {
    if (line.size() + 1 + word.size() > kWidth && line.back() != '#') {
      out += line + "\n";
      line = std::string(kColumn, ' ') + "#";
    }
    line += " " + word;
  }
  return out + line + "\n";
}

std::vector<std::string> cells(std::string_view row) {
  std::vector<std::string> out;
  if (row.size() < 4 || row.substr(0, 2) != "| " || row.substr(row.size() - 2) != " |") return out;
  row = row.substr(2, row.size() - 4);
  for (std::size_t start = 0;;) {
    const std::size_t end = row.find(" | ", start);
    out.emplace_back(row.substr(start, end - start));
    if (end == std::string_view::npos) return out;
    start = end + 3;
  }
}

}  // namespace

std::string knobsToml() {
  std::string out;
  for (const RenderKnob& knob : renderKnobs())
    out += commented(std::string(knob.name) + " = " + tomlValue(knob, knob.default_value),
                     std::string(knob.doc) + " (" + knob.allowed() + ")");
  return out;
}

std::string knobsMarkdown(const std::vector<std::pair<std::string, std::string>>& measured) {
  std::string out =
      "| knob | default | allowed | swept | turn it for | what it costs |\n"
      "| --- | --- | --- | --- | --- | --- |\n";
  for (const RenderKnob& knob : renderKnobs()) {
    std::string swept;
    for (double v : knob.sweep) swept += (swept.empty() ? "" : ", ") + knob.format(v);
    if (knob.how == KnobSweep::kModel) swept += "; M";  // another model (docs/ACCURACY.md)
    std::string rest = " | ";
    for (const auto& [name, columns] : measured)
      if (name == knob.name) rest = columns;
    out += "| `" + std::string(knob.name) + "` | " + knob.format(knob.default_value) + " | " +
           knob.allowed() + " | " + swept + " | " + rest + " |\n";
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> measuredKnobColumns(std::string_view document) {
  std::vector<std::pair<std::string, std::string>> out;
  std::istringstream lines{std::string(document)};
  for (std::string line; std::getline(lines, line);) {
    const std::vector<std::string> row = cells(line);
    if (row.size() < 6 || row[0].size() < 3 || row[0].front() != '`' || row[0].back() != '`')
      continue;
    const std::string name = row[0].substr(1, row[0].size() - 2);
    if (!findRenderKnob(name)) continue;
    std::string columns;
    for (std::size_t i = 4; i < row.size(); ++i) columns += (i == 4 ? "" : " | ") + row[i];
    out.emplace_back(name, columns);
  }
  return out;
}

}  // namespace nephele
