#include "pipeline/psm_slam_session.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "map/map_store.hpp"

namespace polarslam {
namespace {

// resume-filter.bin: the filter's mean, then its covariance's lower triangle row by row, as the
// doubles of the machine that wrote it (a snapshot is read back where it was written).
constexpr const char* kResumeFilterLayout = "resume-filter.bin: mean, covariance lower triangle by rows, float64";

std::string filterStateBytes(const PsmSlamFilterState& state) {
  std::vector<double> values(state.mean.data(), state.mean.data() + state.mean.size());
  for (Eigen::Index r = 0; r < state.cov.rows(); ++r)
    for (Eigen::Index c = 0; c <= r; ++c) values.push_back(state.cov(r, c));
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
}

void readFilterStateBytes(const std::string& bytes, const std::string& file, PsmSlamFilterState& state) {
  const Eigen::Index n = static_cast<Eigen::Index>(3 * (state.ids.size() + 1));
  const size_t count = static_cast<size_t>(n + n * (n + 1) / 2);
  if (bytes.size() != count * sizeof(double))
    throw MapFormatError(file, "'" + file + "' holds " + std::to_string(bytes.size()) + " bytes; the filter of " +
                                   std::to_string(state.ids.size()) + " keyframes needs " +
                                   std::to_string(count * sizeof(double)));
  std::vector<double> values(count);
  std::memcpy(values.data(), bytes.data(), bytes.size());
  state.mean = Eigen::Map<const Eigen::VectorXd>(values.data(), n);
  state.cov.resize(n, n);
  size_t next = static_cast<size_t>(n);
  for (Eigen::Index r = 0; r < n; ++r)
    for (Eigen::Index c = 0; c <= r; ++c) state.cov(r, c) = state.cov(c, r) = values[next++];
}

}  // namespace

Pose2 parseInitialPose(const std::string& text) {
  std::istringstream in(text);
  double v[3];
  char comma1 = 0, comma2 = 0;
  if (!(in >> v[0] >> comma1 >> v[1] >> comma2 >> v[2]) || comma1 != ',' || comma2 != ',' || !(in >> std::ws).eof() ||
      !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
    throw std::runtime_error("--initial-pose '" + text + "': expected x,y,theta (m, m, rad), three finite numbers");
  return Pose2(v[0], v[1], v[2]);
}

namespace {

StoredMap mapToLoad(const SavedMapOptions& o) { return o.loaded_map ? *o.loaded_map : loadMap(o.load_map); }

/// The estimator working in the map o.load_map.
std::unique_ptr<Estimator> makeMapEstimator(PsmSlamEstimatorConfig config, const SavedMapOptions& o) {
  if (o.mode == "continue") {
    auto estimator =
        std::make_unique<MapContinuationEstimator>(mapToLoad(o), std::move(config), o.initial_pose, o.initial_cov,
                                                   o.filter_seed);
    estimator->saveMapTo(o.save_map);
    return estimator;
  }
  if (o.mode != "localize") throw std::runtime_error("--mode must be localize or continue, not '" + o.mode + "'");
  if (!o.save_map.empty()) throw std::runtime_error("--mode localize adds nothing to the map: no --save-map");
  return std::make_unique<MapLocalizationEstimator>(mapToLoad(o), std::move(config), o.initial_pose,
                                                    o.initial_cov);
}

}  // namespace

std::unique_ptr<Estimator> makePsmSlamEstimator(PsmSlamEstimatorConfig config, const SavedMapOptions& o) {
  if (o.load_map.empty()) {
    if (o.initial_pose) throw std::runtime_error("--initial-pose goes with --load-map");
    auto estimator = std::make_unique<PsmSlamEstimator>(std::move(config));
    estimator->saveMapTo(o.save_map);
    return estimator;
  }
  try {
    return makeMapEstimator(std::move(config), o);
  } catch (const std::length_error& e) {  // a map too wide for its grids: say which
    throw std::length_error("map '" + o.load_map + "': " + e.what());
  }
}

PsmSlamSession::PsmSlamSession(PsmSlamEstimatorConfig config, const SavedMapOptions& options)
    : estimator_(makePsmSlamEstimator(std::move(config), options)), save_map_(options.save_map) {
  scratch_ = dynamic_cast<PsmSlamEstimator*>(estimator_.get());
  continuation_ = dynamic_cast<MapContinuationEstimator*>(estimator_.get());
  localization_ = dynamic_cast<MapLocalizationEstimator*>(estimator_.get());
}

const PsmSlamEstimator* PsmSlamSession::mapping() const {
  if (scratch_) return scratch_;
  if (continuation_ && continuation_->mapping()) return &continuation_->mappingEstimator();
  return nullptr;
}

const PsmSlam* PsmSlamSession::slam() const {
  const PsmSlamEstimator* m = mapping();
  return m ? &m->slam() : nullptr;
}

void PsmSlamSession::onOdometry(const OdometryReading& reading) {
  started_ = true;
  last_odometry_ = reading;
  estimator_->onOdometry(reading);
}

PsmSlamScanOutput PsmSlamSession::onLaser(const LaserScan& scan) {
  started_ = true;
  const bool mapping_before = mapping() != nullptr;
  estimator_->onLaser(scan);
  PsmSlamScanOutput out;
  out.pose = estimator_->onlineTrajectory().back();
  const PsmSlamEstimator* m = mapping();
  if (m && mapping_before) {
    const PsmSlamScanResult& r = m->lastResult();
    out.anchor = r.anchor;
    out.usable = r.usable;
    out.graph_changed = r.new_keyframe || r.loop_closed || r.optimized;
    out.optimized = r.optimized;
  } else {
    // Localising, or the scan that placed a continued map's robot (the graph appears with it).
    out.usable = localization_ ? localization_->lastResult().usable : true;
    out.graph_changed = m != nullptr;
  }
  return out;
}

void PsmSlamSession::saveMapNow() const {
  const PsmSlamEstimator* m = mapping();
  if (!m) throw MapFormatError(save_map_, "nothing to save yet: the robot has not been placed in the map");
  m->saveMapNow();
}

nlohmann::json PsmSlamSession::finish() {
  nlohmann::json report;
  estimator_->finish("", report);
  return report;
}

namespace {

nlohmann::json poseJson(const Pose2& p) { return {p.x, p.y, p.theta}; }
Pose2 poseFromJson(const nlohmann::json& j) { return Pose2(j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()); }

nlohmann::json odometryJson(const OdometryReading& o) {
  return {{"utime", o.utime}, {"seq", o.seq}, {"pose", poseJson(o.pose)}, {"left_travel", o.left_travel},
          {"right_travel", o.right_travel}, {"v", o.v}, {"omega", o.omega}};
}

Mat3 covarianceFromJson(const nlohmann::json& j, const std::string& file) {
  const std::vector<double> values = j.get<std::vector<double>>();
  if (values.size() != 9) throw MapFormatError(file, "'" + file + "': a covariance has 9 numbers");
  return Eigen::Map<const Mat3>(values.data());
}

}  // namespace

void PsmSlamSession::writeSnapshot(const std::string& dir, nlohmann::json resume) const {
  if (last_odometry_) resume["last_odometry"] = odometryJson(*last_odometry_);
  if (localization_) {
    // Localising: the map is unchanged; the pose resumes tracking, or the search goes on.
    resume["mode"] = "localize";
    if (localization_->localized()) {
      const PoseStamped& pose = localization_->lastResult().pose;
      resume["pose"] = poseJson(pose.pose);
      resume["covariance"] = std::vector<double>(pose.cov.data(), pose.cov.data() + 9);
    }
    StoredMap map = localization_->map();
    map.resume_json = resume.dump(1) + "\n";
    return saveMap(dir, map, nullptr);
  }
  const PsmSlamEstimator* m = mapping();
  if (!m) throw MapFormatError(dir, "no map yet: nothing to snapshot");
  resume["mode"] = "continue";
  const PsmSlam& slam = m->slam();
  // For readers of resume.json: the robot's uncertainty relative to its reference scan. The
  // resumed filter itself is resume-filter.bin.
  const Mat3 cov = slam.uncertaintyFromRobot(slam.filter().activeKeyframe());
  resume["pose"] = poseJson(slam.currentPose());
  const PsmSlamFilterSeed seed = slam.filterSeed();
  resume["filter"] = {{"active", seed.filter.active},
                      {"keyframes", seed.filter.ids},
                      {"skeleton", seed.skeleton},
                      {"state", std::string(kResumeFilterLayout)}};
  resume["covariance"] = std::vector<double>(cov.data(), cov.data() + 9);
  StoredMap map = m->storedMap();
  map.resume_json = resume.dump(1) + "\n";
  map.resume_filter = filterStateBytes(seed.filter);
  saveMap(dir, map, nullptr);
}

namespace {

/// A snapshot written before resume-filter.bin held, per reference scan in the filter, only its
/// covariance as seen from the robot: resumed as that, uncorrelated, at the map's poses, every one
/// kept for loop closure (what those versions did), so that an upgrade loses no run.
PsmSlamFilterSeed olderFilterSeed(const nlohmann::json& filter, const SavedMapOptions& options, const PoseGraph& graph,
                                  const std::string& file) {
  if (!options.initial_pose) throw MapFormatError(file, "'" + file + "': a mapping snapshot without a pose");
  const nlohmann::json& keyframes = filter.at("keyframes");
  PsmSlamFilterSeed seed;
  seed.filter.active = filter.at("active").get<int64_t>();
  const Eigen::Index n = static_cast<Eigen::Index>(3 * (keyframes.size() + 1));
  seed.filter.mean.resize(n);
  seed.filter.cov = Eigen::MatrixXd::Zero(n, n);
  seed.filter.mean.head<3>() = options.initial_pose->vec();
  seed.filter.cov.topLeftCorner<3, 3>() = options.initial_cov;
  Eigen::Index row = 3;
  for (const nlohmann::json& k : keyframes) {
    const int64_t id = k.at("id").get<int64_t>();
    if (graph.indexOf(id) < 0)
      throw MapFormatError(file, "'" + file + "': filter keyframe " + std::to_string(id) + " is not a graph node");
    seed.filter.ids.push_back(id);
    seed.skeleton.push_back(id);
    seed.filter.mean.segment<3>(row) = graph.node(id).pose.vec();
    seed.filter.cov.block<3, 3>(row, row) = covarianceFromJson(k.at("covariance"), file);
    row += 3;
  }
  return seed;
}

}  // namespace

std::optional<SessionSnapshot> readSessionSnapshot(const std::string& dir, const SavedMapOptions& options) {
  if (!std::filesystem::exists(dir)) return std::nullopt;
  auto map = std::make_shared<const StoredMap>(loadMap(dir));
  SessionSnapshot snapshot = sessionSnapshotOf(*map, dir, options);
  snapshot.options.loaded_map = std::move(map);
  return snapshot;
}

SessionSnapshot sessionSnapshotOf(const StoredMap& map, const std::string& dir, const SavedMapOptions& options) {
  const std::string file = dir + "/resume.json";
  if (map.resume_json.empty()) throw MapFormatError(file, "'" + dir + "' is a map, not a snapshot: no resume.json");
  SessionSnapshot snapshot;
  try {
    snapshot.resume = nlohmann::json::parse(map.resume_json);
    snapshot.options.load_map = dir;
    snapshot.options.mode = snapshot.resume.at("mode").get<std::string>();
    if (snapshot.options.mode != "localize" && snapshot.options.mode != "continue")
      throw MapFormatError(file, "'" + file + "': mode must be localize or continue");
    if (snapshot.resume.contains("pose")) {
      snapshot.options.initial_pose = poseFromJson(snapshot.resume.at("pose"));
      snapshot.options.initial_cov = covarianceFromJson(snapshot.resume.at("covariance"), file);
    }
    if (snapshot.options.mode == "continue") {
      snapshot.options.save_map = options.save_map;
      const nlohmann::json& filter = snapshot.resume.at("filter");
      if (!filter.contains("state")) {
        snapshot.options.filter_seed = olderFilterSeed(filter, snapshot.options, map.graph, file);
      } else {
        if (filter.at("state").get<std::string>() != kResumeFilterLayout)
          throw MapFormatError(file, "'" + file + "': unknown filter layout " + filter.at("state").dump());
        PsmSlamFilterSeed seed;
        seed.filter.active = filter.at("active").get<int64_t>();
        seed.filter.ids = filter.at("keyframes").get<std::vector<int64_t>>();
        seed.skeleton = filter.at("skeleton").get<std::vector<int64_t>>();
        readFilterStateBytes(map.resume_filter, dir + "/resume-filter.bin", seed.filter);
        snapshot.options.filter_seed = seed;
      }
    }
    if (snapshot.resume.contains("last_odometry")) {
      const nlohmann::json& o = snapshot.resume["last_odometry"];
      OdometryReading r;
      r.utime = o.at("utime").get<int64_t>();
      r.seq = o.at("seq").get<int64_t>();
      r.pose = poseFromJson(o.at("pose"));
      r.left_travel = o.at("left_travel").get<double>();
      r.right_travel = o.at("right_travel").get<double>();
      r.v = o.at("v").get<double>();
      r.omega = o.at("omega").get<double>();
      snapshot.last_odometry = r;
    }
  } catch (const nlohmann::json::exception& e) {
    throw MapFormatError(file, "'" + file + "': " + e.what());
  }
  return snapshot;
}

}  // namespace polarslam
