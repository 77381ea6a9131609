#include "map/map_store.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <Eigen/Eigenvalues>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

#include "grid/grid_files.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace fs = std::filesystem;

namespace {

const char* const kManifest = "manifest.json";
const char* const kGraphFile = "graph.txt";
const char* const kScansFile = "scans.txt";
const char* const kParametersFile = "parameters.yaml";
const char* const kResumeFile = "resume.json";
const char* const kResumeFilterFile = "resume-filter.bin";
const char* const kUncertaintyFile = "uncertainty.json";

std::string uncertaintyJson(const std::vector<std::pair<int64_t, Mat3>>& covariances) {
  nlohmann::json nodes = nlohmann::json::array();
  for (const auto& [id, cov] : covariances) nodes.push_back({{"id", id}, {"covariance", std::vector<double>(cov.data(), cov.data() + 9)}});
  return nlohmann::json{{"node_covariances", nodes}}.dump(1) + "\n";
}

std::vector<std::pair<int64_t, Mat3>> parseUncertainty(const std::string& text, const std::string& file,
                                                       const PoseGraph& graph) {
  std::vector<std::pair<int64_t, Mat3>> out;
  try {
    const nlohmann::json parsed = nlohmann::json::parse(text);  // kept alive through the loop
    for (const nlohmann::json& node : parsed.at("node_covariances")) {
      const int64_t id = node.at("id").get<int64_t>();
      const std::vector<double> values = node.at("covariance").get<std::vector<double>>();
      if (values.size() != 9) throw MapFormatError(file, "'" + file + "': a covariance has 9 numbers");
      const Mat3 cov = Eigen::Map<const Mat3>(values.data());
      if (graph.indexOf(id) < 0) throw MapFormatError(file, "'" + file + "': node " + std::to_string(id) + " is not in the graph");
      if (!cov.allFinite() || Eigen::SelfAdjointEigenSolver<Mat3>(0.5 * (cov + cov.transpose())).eigenvalues().minCoeff() <= 0.0)
        throw MapFormatError(file, "'" + file + "': node " + std::to_string(id) + " has no positive definite covariance");
      out.emplace_back(id, cov);
    }
  } catch (const nlohmann::json::exception& e) {
    throw MapFormatError(file, "'" + file + "': " + e.what());
  }
  return out;
}

// ---- numbers that read back bit for bit ------------------------------------------------------

template <typename T>
void appendNumber(std::string& out, T value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
  out.push_back(' ');
}

template <typename T>
std::optional<T> parseNumber(std::string_view field) {
  T value{};
  const auto result = std::from_chars(field.data(), field.data() + field.size(), value);
  if (result.ec != std::errc() || result.ptr != field.data() + field.size()) return std::nullopt;
  return value;
}

/// Fields of one record, read in order; each failure names the file and line.
class FieldReader {
 public:
  FieldReader(std::vector<std::string_view> fields, const std::string& file, int line)
      : fields_(std::move(fields)), file_(file), line_(line) {}

  template <typename T>
  T next(const char* what) {
    if (index_ >= fields_.size()) fail(std::string("record ends before its ") + what);
    const std::optional<T> value = parseNumber<T>(fields_[index_]);
    if (!value) fail(std::string("bad ") + what + " '" + std::string(fields_[index_]) + "'");
    ++index_;
    return *value;
  }
  double finite(const char* what) {
    const double value = next<double>(what);
    if (!std::isfinite(value)) fail(std::string(what) + " is not finite");
    return value;
  }
  Pose2 pose(const char* what) {
    const double x = finite(what), y = finite(what), theta = finite(what);
    return {x, y, theta};
  }
  void expectEnd() {
    if (index_ != fields_.size()) fail("unexpected extra fields");
  }
  [[noreturn]] void fail(const std::string& message) const { throw TextFormatError(file_, line_, message); }

 private:
  std::vector<std::string_view> fields_;
  size_t index_ = 1;  // field 0 is the record tag
  std::string file_;
  int line_;
};

// ---- graph.txt and scans.txt -----------------------------------------------------------------

void appendPose(std::string& out, const Pose2& pose) {
  appendNumber(out, pose.x);
  appendNumber(out, pose.y);
  appendNumber(out, pose.theta);
}

void endRecord(std::string& out) { out.back() = '\n'; }

std::string graphText(const PoseGraph& graph) {
  std::string out = "# polarslam pose graph: node ID UTIME X Y THETA\n"
                    "# edge FROM TO KIND ACTIVE X Y THETA COVARIANCE(9, row-major)\n";
  for (const PoseGraphNode& node : graph.nodes()) {
    out += "node ";
    appendNumber(out, node.id);
    appendNumber(out, node.utime);
    appendPose(out, node.pose);
    endRecord(out);
  }
  for (const PoseGraphEdge& edge : graph.edges()) {
    out += "edge ";
    appendNumber(out, edge.from);
    appendNumber(out, edge.to);
    appendNumber(out, static_cast<int>(edge.kind));
    appendNumber(out, edge.active ? 1 : 0);
    appendPose(out, edge.measurement);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) appendNumber(out, edge.covariance(r, c));
    endRecord(out);
  }
  return out;
}

std::string scansText(const std::vector<MapReferenceScan>& scans) {
  std::string out =
      "# polarslam reference scans: scan UTIME SEQ ANGLE_MIN ANGLE_INCREMENT TIME_INCREMENT RANGE_MAX\n"
      "#   MOUNT(x y theta) ANCHOR_NODE RELATIVE(x y theta) NEW_NODE BEAMS RANGES...\n";
  for (const MapReferenceScan& reference : scans) {
    const LaserScan& s = reference.scan;
    out += "scan ";
    appendNumber(out, s.utime);
    appendNumber(out, s.seq);
    appendNumber(out, s.angle_min);
    appendNumber(out, s.angle_increment);
    appendNumber(out, s.time_increment);
    appendNumber(out, s.range_max);
    appendPose(out, s.laser_pose);
    appendNumber(out, reference.anchor.node);
    appendPose(out, reference.anchor.relative);
    appendNumber(out, reference.anchor.new_node ? 1 : 0);
    appendNumber(out, s.ranges.size());
    for (float range : s.ranges) appendNumber(out, range);
    endRecord(out);
  }
  return out;
}

PoseGraph parseGraph(const std::string& text, const std::string& file) {
  PoseGraph graph;
  std::vector<PoseGraphEdge> edges;
  forEachDataLine(text, file, [&](int line, std::string_view content) {
    FieldReader in(splitFields(content), file, line);
    const std::string_view tag = splitFields(content).front();
    if (tag == "node") {
      PoseGraphNode node;
      node.id = in.next<int64_t>("node id");
      node.utime = in.next<int64_t>("utime");
      node.pose = in.pose("pose");
      in.expectEnd();
      if (graph.indexOf(node.id) >= 0) in.fail("node " + std::to_string(node.id) + " listed twice");
      try {
        graph.addNode(node);  // ids must increase
      } catch (const std::invalid_argument& e) {
        in.fail(e.what());
      }
      return;
    }
    if (tag != "edge") in.fail("unknown record '" + std::string(tag) + "'");
    PoseGraphEdge edge;
    edge.from = in.next<int64_t>("from");
    edge.to = in.next<int64_t>("to");
    const int kind = in.next<int>("kind");
    if (!isEdgeKind(kind)) in.fail("unknown edge kind");
    edge.kind = static_cast<PoseGraphEdgeKind>(kind);
    const int active = in.next<int>("active flag");
    if (active != 0 && active != 1) in.fail("active flag must be 0 or 1");
    edge.active = active == 1;
    edge.measurement = in.pose("measurement");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) edge.covariance(r, c) = in.finite("covariance");
    in.expectEnd();
    try {
      graph.addEdge(edge);
    } catch (const std::invalid_argument& e) {
      in.fail(e.what());
    }
  });
  return graph;
}

std::vector<MapReferenceScan> parseScans(const std::string& text, const std::string& file) {
  std::vector<MapReferenceScan> scans;
  forEachDataLine(text, file, [&](int line, std::string_view content) {
    const std::vector<std::string_view> fields = splitFields(content);
    FieldReader in(fields, file, line);
    if (fields.front() != "scan") in.fail("unknown record '" + std::string(fields.front()) + "'");
    MapReferenceScan reference;
    LaserScan& s = reference.scan;
    s.utime = in.next<int64_t>("utime");
    s.seq = in.next<int64_t>("seq");
    s.angle_min = in.finite("angle_min");
    s.angle_increment = in.finite("angle_increment");
    s.time_increment = in.finite("time_increment");
    s.range_max = in.finite("range_max");
    s.laser_pose = in.pose("mount");
    reference.anchor.utime = s.utime;
    reference.anchor.node = in.next<int64_t>("anchor node");
    reference.anchor.relative = in.pose("relative pose");
    const int new_node = in.next<int>("new-node flag");
    if (new_node != 0 && new_node != 1) in.fail("new-node flag must be 0 or 1");
    reference.anchor.new_node = new_node == 1;
    const size_t beams = in.next<size_t>("beam count");
    if (beams > kMaxLaserBeams) in.fail("more than " + std::to_string(kMaxLaserBeams) + " beams");
    s.ranges.reserve(beams);
    for (size_t i = 0; i < beams; ++i) s.ranges.push_back(in.next<float>("range"));
    in.expectEnd();
    if (const std::string problem = validateScan(s); !problem.empty()) in.fail(problem);
    scans.push_back(std::move(reference));
  });
  return scans;
}

// ---- manifest --------------------------------------------------------------------------------

nlohmann::json laserJson(const LaserGeometry& laser) {
  return {{"angle_min", laser.angle_min},
          {"angle_increment", laser.angle_increment},
          {"beams", laser.beams},
          {"range_max", laser.range_max},
          {"mount", {laser.mount.x, laser.mount.y, laser.mount.theta}}};
}

LaserGeometry laserFromJson(const nlohmann::json& j) {
  LaserGeometry laser;
  laser.angle_min = j.at("angle_min").get<double>();
  laser.angle_increment = j.at("angle_increment").get<double>();
  laser.beams = j.at("beams").get<size_t>();
  laser.range_max = j.at("range_max").get<double>();
  const auto& mount = j.at("mount");
  if (!mount.is_array() || mount.size() != 3) throw std::runtime_error("laser mount must be [x, y, theta]");
  laser.mount = Pose2(mount[0].get<double>(), mount[1].get<double>(), mount[2].get<double>());
  return laser;
}

// ---- durable files ---------------------------------------------------------------------------

std::string systemError(const std::string& what, const std::string& path) {
  return what + " '" + path + "': " + std::strerror(errno);
}

void fsyncPath(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
  if (fd < 0) throw MapFormatError(path, systemError("cannot open", path));
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (!synced) throw MapFormatError(path, systemError("cannot fsync", path));
}

void writeDurably(const std::string& path, const std::string& content) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw MapFormatError(path, systemError("cannot create", path));
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string message = systemError("cannot write", path);
      ::close(fd);
      throw MapFormatError(path, message);
    }
    written += static_cast<size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  const bool closed = ::close(fd) == 0;
  if (!synced || !closed) throw MapFormatError(path, systemError("cannot flush", path));
}

std::string readMapFile(const std::string& path) {
  try {
    return readTextFile(path);
  } catch (const std::exception& e) {
    throw MapFormatError(path, e.what());
  }
}

void validateForSaving(const StoredMap& map) {
  for (const MapReferenceScan& reference : map.scans) {
    const std::string mismatch = laserGeometryMismatch(map.laser, laserGeometryOf(reference.scan));
    if (!mismatch.empty())
      throw MapFormatError(kScansFile, "scan at utime " + std::to_string(reference.scan.utime) +
                                           " does not match the map's laser: " + mismatch);
    if (reference.anchor.node >= 0 && map.graph.indexOf(reference.anchor.node) < 0)
      throw MapFormatError(kScansFile, "scan at utime " + std::to_string(reference.scan.utime) +
                                           " is anchored to node " + std::to_string(reference.anchor.node) +
                                           ", which the graph lacks");
  }
}

/// Puts the finished folder `temporary` at `dir`: one atomic exchange when a map is there
/// already (Linux renameat2), a plain rename otherwise. Returns the folder to delete.
std::string swapIn(const std::string& temporary, const std::string& dir) {
  if (!fs::exists(dir)) {
    if (std::rename(temporary.c_str(), dir.c_str()) != 0) throw MapFormatError(dir, systemError("cannot create", dir));
    return {};
  }
  if (::renameat2(AT_FDCWD, temporary.c_str(), AT_FDCWD, dir.c_str(), RENAME_EXCHANGE) == 0) return temporary;
  // No exchange on this file system: the old map steps aside only after the new one is complete.
  const std::string old = dir + ".old-" + std::to_string(::getpid());
  if (std::rename(dir.c_str(), old.c_str()) != 0) throw MapFormatError(dir, systemError("cannot move aside", dir));
  if (std::rename(temporary.c_str(), dir.c_str()) != 0) {
    const std::string message = systemError("cannot replace", dir);
    std::rename(old.c_str(), dir.c_str());
    throw MapFormatError(dir, message);
  }
  return old;
}

void writeMapFolder(const std::string& folder, const StoredMap& map, const OccupancyGrid* grid) {
  nlohmann::json files = nlohmann::json::object();
  auto add = [&](const std::string& name, const std::string& content) {
    writeDurably(folder + "/" + name, content);
    files[name] = {{"bytes", content.size()}, {"crc32", mapCrc32(content)}};
  };
  add(kGraphFile, graphText(map.graph));
  add(kScansFile, scansText(map.scans));
  add(kParametersFile, map.parameters_yaml);
  if (!map.resume_json.empty()) add(kResumeFile, map.resume_json);
  if (!map.resume_filter.empty()) add(kResumeFilterFile, map.resume_filter);
  if (!map.node_covariances.empty()) add(kUncertaintyFile, uncertaintyJson(map.node_covariances));
  if (grid) {
    const GridFiles written = writeGridFiles(folder, *grid);
    for (const std::string& path : {written.ot, written.bt, written.pgm, written.yaml, written.png}) {
      fsyncPath(path, false);
      const std::string content = readMapFile(path);
      files[fs::path(path).filename().string()] = {{"bytes", content.size()}, {"crc32", mapCrc32(content)}};
    }
  }
  nlohmann::json manifest = {{"format", kMapFormatName},
                             {"version", kMapFormatVersion},
                             {"laser", laserJson(map.laser)},
                             {"nodes", map.graph.nodes().size()},
                             {"edges", map.graph.edges().size()},
                             {"scans", map.scans.size()},
                             {"files", files}};
  writeDurably(folder + "/" + kManifest, manifest.dump(2) + "\n");
  fsyncPath(folder, true);
}

// ---- loading ---------------------------------------------------------------------------------

nlohmann::json readManifest(const std::string& dir) {
  const std::string path = dir + "/" + kManifest;
  if (!fs::is_directory(dir)) throw MapFormatError(dir, "'" + dir + "' is not a map folder");
  if (!fs::exists(path)) throw MapFormatError(path, "'" + path + "' is missing: not a polarslam map");
  nlohmann::json manifest;
  try {
    manifest = nlohmann::json::parse(readMapFile(path));
  } catch (const nlohmann::json::exception& e) {
    throw MapFormatError(path, "'" + path + "' is not valid JSON (truncated?): " + e.what());
  }
  if (!manifest.is_object() || manifest.value("format", std::string()) != kMapFormatName)
    throw MapFormatError(path, "'" + path + "' is not a " + kMapFormatName + " manifest");
  const auto version = manifest.find("version");
  if (version == manifest.end() || !version->is_number_integer() || version->get<int>() != kMapFormatVersion)
    throw MapFormatError(path, "'" + path + "' has format version " +
                                   (version == manifest.end() ? std::string("(none)") : version->dump()) +
                                   "; this build reads version " + std::to_string(kMapFormatVersion));
  return manifest;
}

/// Reads a file the manifest lists, checking its size and checksum.
std::string readCheckedFile(const std::string& dir, const nlohmann::json& files, const std::string& name) {
  const std::string path = dir + "/" + name;
  const auto entry = files.find(name);
  if (entry == files.end()) throw MapFormatError(path, "the manifest does not list '" + name + "'");
  if (!fs::exists(path)) throw MapFormatError(path, "'" + path + "' is missing");
  const std::string content = readMapFile(path);
  const auto bytes = entry->at("bytes").get<size_t>();
  if (content.size() != bytes)
    throw MapFormatError(path, "'" + path + "' has " + std::to_string(content.size()) + " bytes, the manifest says " +
                                   std::to_string(bytes) + (content.size() < bytes ? " (truncated)" : ""));
  const auto crc = entry->at("crc32").get<uint32_t>();
  if (mapCrc32(content) != crc)
    throw MapFormatError(path, "'" + path + "' fails its CRC32 check (corrupted or edited)");
  return content;
}

}  // namespace

MapFormatError::MapFormatError(const std::string& file, const std::string& message)
    : std::runtime_error(message.find(file) == std::string::npos ? file + ": " + message : message), file_(file) {}

uint32_t mapCrc32(const std::string& bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  size_t done = 0;
  while (done < bytes.size()) {  // zlib takes uInt lengths
    const uInt chunk = static_cast<uInt>(std::min<size_t>(bytes.size() - done, 1u << 30));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + done), chunk);
    done += chunk;
  }
  return static_cast<uint32_t>(crc);
}

LaserGeometry laserGeometryOf(const LaserScan& scan) {
  return {scan.angle_min, scan.angle_increment, scan.ranges.size(), scan.range_max, scan.laser_pose};
}

std::string laserGeometryMismatch(const LaserGeometry& expected, const LaserGeometry& actual) {
  constexpr double kTolerance = 1e-6;
  auto differs = [](double a, double b) { return !(std::abs(a - b) <= kTolerance); };
  auto show = [](double a, double b) { return std::to_string(a) + " here, " + std::to_string(b) + " in the map"; };
  if (expected.beams != actual.beams)
    return "beam count " + std::to_string(actual.beams) + " here, " + std::to_string(expected.beams) + " in the map";
  if (differs(expected.angle_min, actual.angle_min)) return "angle_min " + show(actual.angle_min, expected.angle_min);
  if (differs(expected.angle_increment, actual.angle_increment))
    return "angle_increment " + show(actual.angle_increment, expected.angle_increment);
  if (differs(expected.range_max, actual.range_max)) return "range_max " + show(actual.range_max, expected.range_max);
  if (differs(expected.mount.x, actual.mount.x) || differs(expected.mount.y, actual.mount.y) ||
      differs(expected.mount.theta, actual.mount.theta))
    return "laser mount differs";
  return {};
}

StoredMap storedMapOf(const PoseGraph& graph, const std::vector<LaserScan>& scans,
                      const std::vector<AnchoredPose>& anchors, std::string parameters_yaml) {
  if (scans.size() != anchors.size()) throw std::invalid_argument("storedMapOf: one anchor per scan");
  StoredMap map;
  map.graph = graph;
  map.parameters_yaml = std::move(parameters_yaml);
  for (size_t i = 0; i < scans.size(); ++i)
    if (anchors[i].new_node && graph.indexOf(anchors[i].node) >= 0) map.scans.push_back({scans[i], anchors[i]});
  if (map.scans.empty()) throw MapFormatError(kScansFile, "no reference scans: nothing to save as a map");
  map.laser = laserGeometryOf(map.scans.front().scan);
  validateForSaving(map);
  return map;
}

void saveMap(const std::string& dir, const StoredMap& map, const OccupancyGrid* grid) {
  validateForSaving(map);
  if (fs::exists(dir) && !fs::exists(dir + "/" + kManifest))
    throw MapFormatError(dir, "'" + dir + "' exists and is not a polarslam map: not replacing it");
  const fs::path parent = fs::absolute(dir).parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  const std::string temporary = dir + ".saving-" + std::to_string(::getpid());
  fs::remove_all(temporary, ec);
  if (!fs::create_directory(temporary, ec)) throw MapFormatError(temporary, "cannot create '" + temporary + "'");
  std::string leftover = temporary;
  try {
    writeMapFolder(temporary, map, grid);
    leftover = swapIn(temporary, dir);
    fsyncPath(parent.string(), true);
  } catch (const MapFormatError&) {
    fs::remove_all(temporary, ec);
    throw;
  } catch (const std::exception& e) {
    fs::remove_all(temporary, ec);
    throw MapFormatError(dir, std::string("cannot save the map: ") + e.what());
  }
  if (!leftover.empty()) fs::remove_all(leftover, ec);
}

StoredMap loadMap(const std::string& dir, const std::optional<LaserGeometry>& expected_laser) {
  const nlohmann::json manifest = readManifest(dir);
  const std::string manifest_path = dir + "/" + kManifest;
  StoredMap map;
  nlohmann::json files;
  try {
    files = manifest.at("files");
    map.laser = laserFromJson(manifest.at("laser"));
    for (const auto& [name, entry] : files.items()) {
      if (name.empty() || name == "." || name == ".." || name.find_first_of("/\\") != std::string::npos)
        throw MapFormatError(manifest_path, "'" + manifest_path + "' lists '" + name + "', not a file of the map folder");
      readCheckedFile(dir, files, name);
    }
  } catch (const nlohmann::json::exception& e) {
    throw MapFormatError(manifest_path, "'" + manifest_path + "' is incomplete: " + e.what());
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const MapFormatError*>(&e)) throw;
    throw MapFormatError(manifest_path, "'" + manifest_path + "': " + e.what());
  }
  if (expected_laser) {
    const std::string mismatch = laserGeometryMismatch(map.laser, *expected_laser);
    if (!mismatch.empty())
      throw MapFormatError(manifest_path, "'" + manifest_path + "' was made with another laser: " + mismatch);
  }
  const std::string graph_path = dir + "/" + kGraphFile, scans_path = dir + "/" + kScansFile;
  try {
    map.graph = parseGraph(readCheckedFile(dir, files, kGraphFile), graph_path);
    map.scans = parseScans(readCheckedFile(dir, files, kScansFile), scans_path);
  } catch (const TextFormatError& e) {
    throw MapFormatError(e.file(), e.what());
  }
  map.parameters_yaml = readCheckedFile(dir, files, kParametersFile);
  if (files.contains(kResumeFile)) map.resume_json = readCheckedFile(dir, files, kResumeFile);
  if (files.contains(kResumeFilterFile)) map.resume_filter = readCheckedFile(dir, files, kResumeFilterFile);
  if (files.contains(kUncertaintyFile))
    map.node_covariances =
        parseUncertainty(readCheckedFile(dir, files, kUncertaintyFile), dir + "/" + kUncertaintyFile, map.graph);
  for (const MapReferenceScan& reference : map.scans) {
    const std::string mismatch = laserGeometryMismatch(map.laser, laserGeometryOf(reference.scan));
    if (!mismatch.empty())
      throw MapFormatError(scans_path, "'" + scans_path + "': scan at utime " + std::to_string(reference.scan.utime) +
                                           " does not match the manifest's laser: " + mismatch);
    if (reference.anchor.node >= 0 && map.graph.indexOf(reference.anchor.node) < 0)
      throw MapFormatError(scans_path, "'" + scans_path + "': scan at utime " + std::to_string(reference.scan.utime) +
                                           " is anchored to node " + std::to_string(reference.anchor.node) +
                                           ", which graph.txt lacks");
  }
  return map;
}

std::vector<MapReference> mapReferences(const StoredMap& map) {
  std::vector<MapReference> references;
  references.reserve(map.scans.size());
  for (const MapReferenceScan& s : map.scans) {
    const int64_t node = s.anchor.node;
    const Pose2 pose = node >= 0 && map.graph.indexOf(node) >= 0 ? map.graph.node(node).pose * s.anchor.relative
                                                                  : s.anchor.relative;
    references.push_back({node, pose, s.scan});
  }
  return references;
}

}  // namespace polarslam
