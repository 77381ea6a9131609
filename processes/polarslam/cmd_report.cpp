// polarslam report DIR: one page a person reads in a browser, from the run folders in DIR
// (each written by `polarslam run`): the figures of every report.json and every PNG plot, the
// pictures embedded so that the page travels on its own.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "command_registry.hpp"
#include "io/atomic_file.hpp"

namespace polarslam {
namespace {

namespace fs = std::filesystem;

std::string escapeHtml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t group = 0;
    for (size_t k = 0; k < 3; ++k) group = (group << 8) | (k < n ? static_cast<uint8_t>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(group >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

/// The picture inside the page (a data: URL), so the report still shows everything when copied
/// or mailed on its own.
std::string embeddedPng(const fs::path& image) {
  std::ifstream in(image, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return "data:image/png;base64," + base64(bytes.str());
}

std::string formatValue(const nlohmann::json& value) {
  if (value.is_number_float()) {
    std::ostringstream s;
    s.precision(4);
    s << value.get<double>();
    return s.str();
  }
  return escapeHtml(value.is_string() ? value.get<std::string>() : value.dump());
}

/// Flattens nested objects into "a.b.c" rows.
void tableRows(const nlohmann::json& node, const std::string& prefix, std::ostream& html) {
  for (const auto& [key, value] : node.items()) {
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (value.is_object()) tableRows(value, name, html);
    else if (!value.is_array() || value.size() <= 8)
      html << "<tr><td>" << escapeHtml(name) << "</td><td>" << formatValue(value) << "</td></tr>\n";
  }
}

/// report.json key and column heading. Final: after the last map or graph; online: as published
/// at scan time; dropped: sequence gaps the live processes counted.
const std::pair<const char*, const char*> kSummaryKeys[] = {
    {"ate_rmse_m", "final ATE RMSE [m]"}, {"online_ate_rmse_m", "online ATE RMSE [m]"},
    {"max_error_m", "final max error [m]"}, {"realtime_factor", "× real time"},
    {"trajectory_poses", "poses"},         {"messages_dropped", "messages dropped (live)"}};

void summaryTable(const std::vector<std::pair<std::string, nlohmann::json>>& runs, std::ostream& html) {
  html << "<h2>Summary</h2><table><tr><th>pipeline</th>";
  for (const auto& [key, heading] : kSummaryKeys) html << "<th>" << heading << "</th>";
  html << "</tr>\n";
  for (const auto& [name, report] : runs) {
    html << "<tr><td>" << escapeHtml(name) << "</td>";
    for (const auto& [key, heading] : kSummaryKeys)
      html << "<td>" << (report.contains(key) ? formatValue(report[key]) : "–") << "</td>";
    html << "</tr>\n";
  }
  html << "</table>\n";
}

/// The same summary as plain text, for the terminal.
void printSummary(const std::vector<std::pair<std::string, nlohmann::json>>& runs, std::ostream& out) {
  out << std::left << std::setw(16) << "run";
  for (const auto& [key, heading] : kSummaryKeys) out << std::setw(24) << heading;
  out << "\n";
  for (const auto& [name, report] : runs) {
    out << std::setw(16) << name;
    for (const auto& [key, heading] : kSummaryKeys) out << std::setw(24) << (report.contains(key) ? formatValue(report[key]) : "-");
    out << "\n";
  }
}

void runSection(const fs::path& dir, const fs::path& root, const nlohmann::json& report, std::ostream& html) {
  html << "<section><h2>" << escapeHtml(dir.filename().string()) << "</h2>\n<div class=plots>";
  std::vector<fs::path> images;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().extension() == ".png") images.push_back(entry.path());
  std::sort(images.begin(), images.end());
  for (const auto& image : images) {
    const std::string rel = fs::relative(image, root).string();
    html << "<figure><img src=\"" << embeddedPng(image) << "\" alt=\"" << escapeHtml(rel) << "\"><figcaption>"
         << escapeHtml(image.filename().string()) << "</figcaption></figure>\n";
  }
  html << "</div><details><summary>all figures</summary><table>\n";
  tableRows(report, "", html);
  html << "</table></details></section>\n";
}

void writeReport(const std::string& root_dir, const std::string& title) {
  const fs::path root(root_dir);
  std::vector<fs::path> dirs;
  for (const auto& entry : fs::directory_iterator(root))
    if (entry.is_directory() && fs::exists(entry.path() / "report.json")) dirs.push_back(entry.path());
  if (fs::exists(root / "report.json")) dirs.push_back(root);
  if (dirs.empty()) throw std::runtime_error("no report.json under '" + root_dir + "'");
  std::sort(dirs.begin(), dirs.end());
  std::vector<std::pair<std::string, nlohmann::json>> runs;
  for (const auto& dir : dirs) {
    std::ifstream in(dir / "report.json");
    nlohmann::json report = nlohmann::json::parse(in, nullptr, false);
    if (report.is_discarded()) throw std::runtime_error("malformed JSON in '" + (dir / "report.json").string() + "'");
    runs.emplace_back(dir.filename().string(), std::move(report));
  }
  std::ostringstream html;
  html << "<!doctype html><html><head><meta charset=utf-8><title>" << escapeHtml(title) << "</title><style>"
       << "body{font-family:sans-serif;margin:2em;color:#222}table{border-collapse:collapse;margin:1em 0}"
       << "td,th{border:1px solid #ccc;padding:3px 8px;text-align:left}.plots{display:flex;flex-wrap:wrap;gap:1em}"
       << "figure{margin:0}img{max-width:640px;border:1px solid #ddd}</style></head><body>\n"
       << "<h1>" << escapeHtml(title) << "</h1>\n";
  summaryTable(runs, html);
  for (size_t i = 0; i < dirs.size(); ++i) runSection(dirs[i], root, runs[i].second, html);
  // Marks the page once every image has loaded (or failed): tests read it with headless Chromium.
  html << "<script>window.addEventListener('load',()=>{const all=[...document.images];"
       << "document.body.dataset.imagesLoaded=all.filter(i=>i.complete&&i.naturalWidth>0).length+'/'+all.length;});"
       << "</script>\n</body></html>\n";
  writeFileAtomically((root / "report.html").string(), html.str());
  printSummary(runs, std::cout);
  std::cout << "wrote " << (root / "report.html").string() << "\n";
}

void setupReport(CLI::App& sub) {
  auto dir = std::make_shared<std::string>();
  auto title = std::make_shared<std::string>("polarslam report");
  sub.add_option("dir", *dir, "folder holding run folders (each with report.json and plots)")->required()->check(CLI::ExistingDirectory);
  sub.add_option("--title", *title, "page title")->capture_default_str();
  sub.callback([dir, title] { writeReport(*dir, *title); });
}

RegisterCommand reg_report("report", "Write report.html (figures and plots) for the run folders in DIR", setupReport);

}  // namespace
}  // namespace polarslam
