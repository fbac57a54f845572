// JSON inputs (specs, scenes, sequence.json) parsed with one kind of message:
// "<source>:<line>:<column>: <problem>", never a library's internal wording.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "shimmer/core/result.h"

namespace shimmer {

// `source` names the text in messages (usually its file name).
Result<nlohmann::json> ParseJson(std::string_view text, const std::string& source);
Result<nlohmann::json> ReadJsonFile(const std::filesystem::path& path);

// `value` dumped on one line, at most `max_chars` long ("..." after): for
// messages that quote what the user wrote.
std::string Quote(const nlohmann::json& value, std::size_t max_chars = 40);

}  // namespace shimmer
