// Implementation of pathctl's output writers.
#include "client/pathctl/output.h"

#include <csv.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "google/protobuf/util/json_util.h"

namespace pathd::pathctl {
namespace {

constexpr struct {
  absl::string_view name;
  OutputFormat format;
} kFormats[] = {
    {"table", OutputFormat::kTable},
    {"json", OutputFormat::kJson},
    {"csv", OutputFormat::kCsv},
    {"geojson", OutputFormat::kGeoJson},
};

bool IsNumber(absl::string_view text) {
  double unused = 0;
  return absl::SimpleAtod(text, &unused);
}

// Quotes one field with libcsv, which doubles the quotes inside it.
std::string QuoteCsvField(const std::string& field) {
  // csv_write returns the size it needs; the worst case is every byte a
  // quote (doubled) plus the two enclosing quotes.
  std::string quoted(2 * field.size() + 2, '\0');
  const size_t size =
      csv_write(quoted.data(), quoted.size(), field.data(), field.size());
  quoted.resize(size);
  return quoted;
}

}  // namespace

absl::StatusOr<OutputFormat> ParseOutputFormat(absl::string_view text) {
  for (const auto& f : kFormats) {
    if (f.name == text) return f.format;
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "--output: unknown format '", text, "'; expected table, json, csv or geojson"));
}

absl::string_view OutputFormatName(OutputFormat format) {
  for (const auto& f : kFormats) {
    if (f.format == format) return f.name;
  }
  return "unknown";
}

absl::StatusOr<OutputFormat> ResolveOutputFormat(const std::string& output,
                                                 bool json) {
  if (output.empty()) return json ? OutputFormat::kJson : OutputFormat::kTable;
  absl::StatusOr<OutputFormat> format = ParseOutputFormat(output);
  if (!format.ok()) return format.status();
  if (json && *format != OutputFormat::kJson) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--json is --output=json; it contradicts --output=", output));
  }
  return *format;
}

Table::Table(std::vector<std::string> header) : header_(std::move(header)) {}

void Table::AddRow(std::vector<std::string> row) {
  // Callers pass full rows; resizing keeps every record as wide as the
  // header even if one does not, so CSV readers never see a ragged file.
  row.resize(header_.size());
  rows_.push_back(std::move(row));
}

std::string Table::Aligned() const {
  const size_t columns = header_.size();
  std::vector<size_t> width(columns);
  std::vector<bool> numeric(columns, !rows_.empty());
  for (size_t c = 0; c < columns; ++c) width[c] = header_[c].size();
  for (const std::vector<std::string>& row : rows_) {
    for (size_t c = 0; c < columns; ++c) {
      width[c] = std::max(width[c], row[c].size());
      if (!IsNumber(row[c])) numeric[c] = false;
    }
  }
  std::string text;
  const auto append_line = [&](const std::vector<std::string>& cells) {
    std::string line;
    for (size_t c = 0; c < columns; ++c) {
      if (c > 0) line.append("  ");
      const std::string padding(width[c] - cells[c].size(), ' ');
      absl::StrAppend(&line, numeric[c] ? padding : "", cells[c],
                      numeric[c] ? "" : padding);
    }
    line.erase(line.find_last_not_of(' ') + 1);
    absl::StrAppend(&text, line, "\n");
  };
  append_line(header_);
  for (const std::vector<std::string>& row : rows_) append_line(row);
  return text;
}

std::string Table::Csv() const {
  std::string text = CsvRecord(header_);
  for (const std::vector<std::string>& row : rows_) {
    absl::StrAppend(&text, CsvRecord(row));
  }
  return text;
}

std::string CsvRecord(const std::vector<std::string>& fields) {
  std::string record;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) record.push_back(',');
    const std::string& field = fields[i];
    // Quoting only where RFC 4180 requires it keeps numbers and names plain
    // for `cut -d,` and friends.
    if (field.find_first_of(",\"\r\n") == std::string::npos) {
      record.append(field);
    } else {
      record.append(QuoteCsvField(field));
    }
  }
  record.push_back('\n');
  return record;
}

std::string FormatNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return absl::StrFormat("%.9g", value);
}

absl::StatusOr<std::string> MessageToJson(
    const google::protobuf::Message& message, bool one_line) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = !one_line;
  options.always_print_primitive_fields = true;
  std::string json;
  const auto status =
      google::protobuf::util::MessageToJsonString(message, &json, options);
  if (!status.ok()) {
    return absl::InternalError(absl::StrCat("cannot print ",
                                            message.GetTypeName(),
                                            " as JSON: ", status.ToString()));
  }
  if (json.empty() || json.back() != '\n') json.push_back('\n');
  return json;
}

}  // namespace pathd::pathctl
