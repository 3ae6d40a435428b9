// Every numeric field of every text reader, given each number at the edges of what int64 and
// binary64 hold: the reader returns a value or an error that names the field, and nothing
// throws past it (issue 26: an integer beyond 2^53 in an add_target centre aborted the
// daemon with std::bad_optional_access). The readers: socket requests (with the cloud and
// target objects of add_cloud and add_target, read on the world thread through the scene-file
// readers), scene files, daemon configs and dataset descriptions. CIGI and Modbus carry
// fixed-size binary numbers; protocol_fuzz and the CIGI tests cover those.
#include <toml++/toml.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "config/scene_file.h"
#include "dataset/dataset_file.h"
#include "protocol/messages.h"
#include "server/daemon_config.h"

namespace nephele {
namespace {

using nlohmann::json;

// The edges, as the text a client or an operator writes. The inexact ones are integers no
// binary64 holds; a reader must refuse them wherever it reads a number.
const std::vector<std::string> kEdges = {"9007199254740993",
                                         "-9007199254740993",
                                         "9223372036854775807",
                                         "-9223372036854775808",
                                         "9223372036854775808",
                                         "18446744073709551616",
                                         "-0",
                                         "-0.0",
                                         "5e-324",
                                         "-5e-324",
                                         "1e308",
                                         "-1.7976931348623157e308",
                                         "1",
                                         "1.0",
                                         "0.5"};
const std::vector<std::string> kTomlEdges = {"9007199254740993",
                                             "9223372036854775807",
                                             "-9223372036854775808",
                                             "-0.0",
                                             "5e-324",
                                             "1e308",
                                             "1",
                                             "1.0"};
bool inexact(const std::string& edge) {
  return edge == "9007199254740993" || edge == "-9007199254740993";
}
// Integer fields, where every int64 may be legal.
bool integerField(const std::string& key) {
  return key == "seed" || key == "subscription";
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A numeric leaf of a JSON document: where it is and the nearest object key above it.
struct Leaf {
  json::json_pointer where;
  std::string key;
};

void numericLeaves(const json& j, const json::json_pointer& at, const std::string& key,
                   std::vector<Leaf>& out) {
  if (j.is_number()) out.push_back({at, key});
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) numericLeaves(*it, at / it.key(), it.key(), out);
  if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i) numericLeaves(j[i], at / i, key, out);
}

// `j` as text with the leaf at `where` written as `edge`, character for character.
std::string withEdge(json j, const json::json_pointer& where, const std::string& edge) {
  const std::string marker = "\"@EDGE@\"";
  j[where] = "@EDGE@";
  const std::string text = j.dump();
  const std::size_t at = text.find(marker);
  return text.substr(0, at) + edge + text.substr(at + marker.size());
}

// What the daemon does with one request line, up to the world: the command, and for add_cloud
// and add_target the object through the scene-file readers. Empty when accepted.
std::string readRequest(const std::string& line) {
  const auto parsed = parseRequest(line);
  if (const auto* bad = std::get_if<BadRequest>(&parsed)) return bad->error.message;
  const Command& command = std::get<Request>(parsed).command;
  if (const auto* c = std::get_if<command::AddCloud>(&command)) {
    EllipsoidCloud cloud;
    return parseCloudJson(c->cloud, 1, cloud);
  }
  if (const auto* t = std::get_if<command::AddTarget>(&command)) {
    Target target;
    return parseTargetJson(t->target, {}, target);
  }
  return "";
}

// Requests with every numeric field the socket protocol has, and an add_cloud for each
// [[cloud]] and an add_target for each [[target]] of the preset scenes.
std::vector<json> requests() {
  std::vector<json> out = {
      json::parse(R"({"id":1,"cmd":"set_view","view":"front","position":[1,2,3],"heading":10,)"
                  R"("pitch":5,"roll":1,"width":64,"height":48,"format":"raw"})"),
      json::parse(R"({"id":1,"cmd":"set_view","view":"front","frustum":)"
                  R"({"left":-20,"right":25,"bottom":-15,"top":10}})"),
      json::parse(R"({"id":1,"cmd":"set_weather","layer":1,"type":7,"base":1000,)"
                  R"("thickness":800,"coverage":40,"wind":[3,4],"centre":[0,0],)"
                  R"("size":[10000,20000],"heading":30,"edge":500,"front":"left",)"
                  R"("transition":300,"spacing":2000,"variation":0.3})"),
      json::parse(R"({"id":1,"cmd":"set_wind","velocity":[3,4]})"),
      json::parse(R"({"id":1,"cmd":"set_sun","azimuth":120,"elevation":30})"),
      json::parse(R"({"id":1,"cmd":"set_fog","top":100,"visibility":500,"colour":[1,1,1]})"),
      json::parse(R"({"id":1,"cmd":"set_sea","fetch":1000,"temperature":10,"clarity":0.5,)"
                  R"("seed":3,"waves":[{"id":2,"height":1,"wavelength":50,"period":5,)"
                  R"("direction":10,"phase":20}]})"),
      json::parse(R"({"id":1,"cmd":"set_time","time_scale":1,"advance":10})"),
      json::parse(R"({"id":1,"cmd":"change_cloud","name":"c","move":[1,2,3],"threshold":0.5,)"
                  R"("limb_threshold":0.4,"transition":0.2,"colour":[1,1,1]})"),
      json::parse(R"({"id":1,"cmd":"add_target","target":{"name":"t","shape":"box",)"
                  R"("centre":[0,0,100],"size":[1,1,1],"heading":3,"pitch":2,"roll":1,)"
                  R"("colour":[0.5,0.5,0.5]}})"),
      json::parse(R"({"id":1,"cmd":"move_target","name":"t","centre":[0,0,1],"heading":1,)"
                  R"("pitch":2,"roll":3})"),
      json::parse(R"({"id":1,"cmd":"tick","dt":0.02})"),
      json::parse(R"({"id":1,"cmd":"render","view":"front","camera":{"position":[0,0,10],)"
                  R"("heading":1,"pitch":2,"roll":3,"vfov":40,"width":8,"height":8}})"),
      json::parse(R"({"id":1,"cmd":"subscribe","view":"front","rate":5})"),
      json::parse(R"({"id":1,"cmd":"unsubscribe","subscription":3})"),
  };
  for (const auto& entry :
       std::filesystem::directory_iterator(NEPHELE_SOURCE_DIR "/config/scenes")) {
    if (entry.path().extension() != ".toml") continue;
    const toml::table scene = toml::parse_file(entry.path().string());
    for (const char* kind : {"cloud", "target"}) {
      const toml::array* tables = scene[kind].as_array();
      if (!tables) continue;
      for (const toml::node& t : *tables) {
        std::ostringstream text;
        text << toml::json_formatter(*t.as_table());
        json object = json::parse(text.str());
        object.erase("develop");  // scene files only
        object.erase("mesh");     // entity types only
        if (object.value("shape", "") == "mesh") continue;
        out.push_back(kind == std::string("cloud")
                          ? json{{"id", 1}, {"cmd", "add_cloud"}, {"cloud", object}}
                          : json{{"id", 1}, {"cmd", "add_target"}, {"target", object}});
      }
    }
  }
  return out;
}

TEST(NumericEdges, EveryRequestFieldRefusesWhatItCannotHoldAndNamesTheField) {
  int tried = 0, refused = 0;
  for (const json& request : requests()) {
    ASSERT_EQ(readRequest(request.dump()), "")
        << "the unaltered request must be accepted: " << request.dump();
    std::vector<Leaf> leaves;
    numericLeaves(request, json::json_pointer(), "", leaves);
    for (const Leaf& leaf : leaves) {
      if (leaf.key == "id") continue;  // any number is a valid id
      for (const std::string& edge : kEdges) {
        const std::string line = withEdge(request, leaf.where, edge);
        std::string error;
        ASSERT_NO_THROW(error = readRequest(line)) << line;
        ++tried;
        if (error.empty()) {
          EXPECT_FALSE(inexact(edge) && !integerField(leaf.key))
              << "accepted a number no double holds: " << line;
          continue;
        }
        ++refused;
        EXPECT_NE(error.find(leaf.key), std::string::npos)
            << "the error does not name " << leaf.key << ": " << error << "\n"
            << line;
      }
    }
  }
  EXPECT_GT(tried, 1000);
  EXPECT_GT(refused, tried / 4);
}

// Numeric values of a TOML document with their place in the text.
struct TomlLeaf {
  std::size_t line, column;  // 1-based, where the value begins
  std::string key;           // the key it belongs to
};

// The first numeric value of each field (a key path, array positions left out: harbour.toml's
// twenty automata have the same fields) not yet `seen` in an earlier file, so every field is
// tried once.
void tomlLeaves(const toml::node& node, const std::string& path, const std::string& key,
                std::set<std::string>& seen, std::vector<TomlLeaf>& out) {
  if (node.is_number() && seen.insert(path).second)
    out.push_back({node.source().begin.line, node.source().begin.column, key});
  if (const toml::table* t = node.as_table())
    for (auto&& [k, v] : *t)
      tomlLeaves(v, path + "." + std::string(k.str()), std::string(k.str()), seen, out);
  if (const toml::array* a = node.as_array())
    for (const toml::node& v : *a) tomlLeaves(v, path, key, seen, out);
}

// `text` with the number beginning at (line, column) written as `edge`.
std::string withTomlEdge(const std::string& text, const TomlLeaf& leaf, const std::string& edge) {
  std::size_t at = 0;
  for (std::size_t line = 1; line < leaf.line; ++line) at = text.find('\n', at) + 1;
  at += leaf.column - 1;
  std::size_t end = at;
  while (end < text.size() &&
         std::string_view("+-0123456789.eE_xobXOBabcdefABCDEFinf").find(text[end]) !=
             std::string_view::npos)
    ++end;
  return text.substr(0, at) + edge + text.substr(end);
}

// Every numeric value of every file a reader takes, each edge in turn.
void checkTomlFiles(
    const std::vector<std::filesystem::path>& files,
    const std::function<std::string(const std::string&, const std::string&)>& read) {
  int tried = 0;
  std::set<std::string> seen;
  for (const auto& path : files) {
    const std::string text = readFile(path);
    ASSERT_EQ(read(text, path.string()), "") << path;
    std::vector<TomlLeaf> leaves;
    tomlLeaves(toml::parse(text, path.string()), "", "", seen, leaves);
    for (const TomlLeaf& leaf : leaves)
      for (const std::string& edge : kTomlEdges) {
        const std::string altered = withTomlEdge(text, leaf, edge);
        std::string error;
        ASSERT_NO_THROW(error = read(altered, path.string())) << path << ":" << leaf.line;
        ++tried;
        if (error.empty()) {
          EXPECT_FALSE(inexact(edge) && !integerField(leaf.key))
              << path << ":" << leaf.line << ": accepted a number no double holds";
          continue;
        }
        EXPECT_NE(error.find(leaf.key), std::string::npos)
            << path << ":" << leaf.line << ": the error does not name " << leaf.key << ": "
            << error;
      }
  }
  EXPECT_GT(tried, 50);
}

std::vector<std::filesystem::path> tomlFilesIn(const char* directory) {
  std::vector<std::filesystem::path> out;
  for (const auto& entry : std::filesystem::directory_iterator(directory))
    if (entry.path().extension() == ".toml") out.push_back(entry.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(NumericEdges, EverySceneFileKeyRefusesWhatItCannotHoldAndNamesTheKey) {
  checkTomlFiles(tomlFilesIn(NEPHELE_SOURCE_DIR "/config/scenes"),
                 [](const std::string& text, const std::string& name) {
                   SceneFile scene;
                   return parseSceneText(text, name, scene);
                 });
}

TEST(NumericEdges, EveryDaemonConfigKeyRefusesWhatItCannotHoldAndNamesTheKey) {
  checkTomlFiles(
      {NEPHELE_SOURCE_DIR "/config/daemon.toml", NEPHELE_SOURCE_DIR "/deploy/nephele.toml"},
      [](const std::string& text, const std::string& name) {
        DaemonConfig config;
        return parseDaemonConfig(text, name, config);
      });
}

TEST(NumericEdges, EveryDatasetKeyRefusesWhatItCannotHoldAndNamesTheKey) {
  checkTomlFiles(tomlFilesIn(NEPHELE_SOURCE_DIR "/config/datasets"),
                 [](const std::string& text, const std::string& name) {
                   DatasetSpec spec;
                   return parseDatasetText(text, name, spec);
                 });
}

}  // namespace
}  // namespace nephele
