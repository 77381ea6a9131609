#pragma once
// JSON Schemas of the foxglove.* message types polarslam-bridge sends with JSON encoding, as
// published by Foxglove (github.com/foxglove/schemas, schemas/jsonschema), plus the bridge's own
// polarslam.ProcessStatus. Foxglove and Lichtblick read them to decode fields: Grid.data is
// base64 ("contentEncoding"), enums are integers.
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace polarslam::foxglove {

/// The schema of `schema_name` ("foxglove.Grid", ...); throws std::invalid_argument when unknown.
nlohmann::json schema(const std::string& schema_name);
/// Every schema name schema() knows.
std::vector<std::string> schemaNames();

}  // namespace polarslam::foxglove
