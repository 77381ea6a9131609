// polarslam match --pairs P.jsonl --out R.jsonl [--method psm|psm-c|icp]: matches scan pairs
// given as JSON lines; one output line per input line (format in core/scanmatch/README.md).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "command_registry.hpp"
#include "common/match_request.hpp"
#include "common/progress.hpp"
#include "io/atomic_file.hpp"
#include "scanmatch/laser_odometry.hpp"
#include "scanmatch/scan_matcher.hpp"

namespace polarslam {
namespace {

using nlohmann::json;

struct MatchOptions {
  std::string pairs, out, method = "psm", covariance = "wls";
  int decimation = 1;
};

json failure(const std::string& status) {
  return {{"pose", nullptr}, {"cov", nullptr}, {"iterations", 0}, {"valid_points", 0}, {"time_us", 0}, {"status", status}};
}

json matchLine(const std::string& text, ScanMatcher& matcher, MatchMethod method) {
  MatchRequest request;
  if (const std::string why = parseMatchRequest(text, request); !why.empty()) return failure(why);
  const LaserScan& ref = request.ref;
  const LaserScan& cur = request.cur;
  const Pose2& guess = request.guess;

  const double start = threadCpuMicros();
  const PreparedScan ref_prepared = prepareScan(ref, matcher.params());
  const PreparedScan cur_prepared = prepareScan(cur, matcher.params());
  const MatchResult m = matcher.match(ref_prepared, cur_prepared, guess, method);
  const double elapsed = threadCpuMicros() - start;

  json out;
  out["pose"] = {m.pose.x, m.pose.y, m.pose.theta};
  if (m.ok()) {
    out["cov"] = json::array();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out["cov"].push_back(m.cov(r, c));
  } else {
    out["cov"] = nullptr;
  }
  out["iterations"] = m.iterations;
  out["valid_points"] = m.valid_points;
  out["time_us"] = std::round(elapsed * 10.0) / 10.0;
  out["status"] = statusText(m.status);
  return out;
}

void runMatch(const MatchOptions& o) {
  PsmParams params;
  if (!parseCovarianceModel(o.covariance, params.covariance)) throw std::runtime_error("unknown covariance " + o.covariance);
  params.decimation = o.decimation;
  MatchMethod method = MatchMethod::Psm;
  if (!parseMatchMethod(o.method, method)) throw std::runtime_error("unknown method " + o.method);
  std::ifstream in(o.pairs, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open '" + o.pairs + "'");
  in.seekg(0, std::ios::end);
  const auto size = static_cast<double>(std::max<std::streamoff>(1, in.tellg()));
  in.seekg(0);

  ScanMatcher matcher(params);
  ProgressBar progress("match");
  std::string text, output;
  std::map<std::string, int> statuses;
  std::vector<double> times;
  double consumed = 0.0;
  while (std::getline(in, text)) {
    consumed += static_cast<double>(text.size() + 1);
    const json result = matchLine(text, matcher, method);
    ++statuses[result["status"].get<std::string>()];
    if (result["status"] == "ok") times.push_back(result["time_us"].get<double>());
    output += result.dump() + "\n";
    progress.update(consumed / size);
  }
  progress.finish();
  writeFileAtomically(o.out, output);

  int lines = 0;
  for (const auto& [status, count] : statuses) lines += count;
  std::cout << "match (" << methodName(method) << ", " << covarianceModelName(params.covariance) << " covariance): "
            << lines << " pairs";
  for (const auto& [status, count] : statuses) std::cout << ", " << count << " " << status;
  if (!times.empty()) {
    std::nth_element(times.begin(), times.begin() + static_cast<long>(times.size() / 2), times.end());
    std::cout << "; median " << times[times.size() / 2] << " us per pair (CPU, including preprocessing)";
  }
  std::cout << " -> " << o.out << "\n";
}

void setupMatch(CLI::App& sub) {
  auto o = std::make_shared<MatchOptions>();
  sub.add_option("--pairs", o->pairs, "JSON lines: {\"ref\": SCAN, \"cur\": SCAN, \"guess\": [x, y, theta]}")
      ->required()->check(CLI::ExistingFile);
  sub.add_option("-o,--out", o->out, "JSON lines, one result per input line")->required();
  sub.add_option("--method", o->method)->check(CLI::IsMember({"psm", "psm-c", "icp"}))->capture_default_str();
  sub.add_option("--covariance", o->covariance)->check(CLI::IsMember({"wls", "heuristic"}))->capture_default_str();
  sub.add_option("--decimation", o->decimation, "use every n-th beam")->check(CLI::Range(1, 16))->capture_default_str();
  sub.callback([o] { runMatch(*o); });
}

RegisterCommand reg_match("match", "Match laser scan pairs from a JSON-lines file (PSM, PSM-C or ICP)", setupMatch);

}  // namespace
}  // namespace polarslam
