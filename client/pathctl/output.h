// pathctl's output formats (--output table|json|csv) and the writers every
// command shares: an aligned text table, CSV records (quoted by libcsv) and
// protobuf's canonical JSON. Commands build their rows once and print them in
// the format the user chose, so a new command gets all three formats by
// filling a Table.
#ifndef PATHD_CLIENT_PATHCTL_OUTPUT_H_
#define PATHD_CLIENT_PATHCTL_OUTPUT_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "google/protobuf/message.h"

namespace pathd::pathctl {

// What --output selects. kTable is the human text each command has always
// printed; kJson is proto3 JSON (the old --json); kCsv a header row and rows.
// kGeoJson (RFC 7946) only for commands that answer with regions
// (isochrone); the others refuse it.
enum class OutputFormat { kTable, kJson, kCsv, kGeoJson };

// "table", "json" or "csv"; INVALID_ARGUMENT naming the flag and the choices.
absl::StatusOr<OutputFormat> ParseOutputFormat(absl::string_view text);

// The --output spelling of `format`.
absl::string_view OutputFormatName(OutputFormat format);

// The format from --output (empty: not given) and its alias --json.
// INVALID_ARGUMENT when --output is not a format or names another format
// than --json asks for.
absl::StatusOr<OutputFormat> ResolveOutputFormat(const std::string& output,
                                                 bool json);

// Rows of text cells under a header. A value type; not thread-safe.
class Table {
 public:
  explicit Table(std::vector<std::string> header);

  // A row of the header's size (missing cells are empty, extra ones dropped).
  void AddRow(std::vector<std::string> row);

  const std::vector<std::string>& header() const { return header_; }
  const std::vector<std::vector<std::string>>& rows() const { return rows_; }

  // The header and rows with every column padded to its widest cell, two
  // spaces apart; columns whose cells are all numbers are right-aligned so
  // digits line up. No trailing spaces.
  std::string Aligned() const;

  // The header record, then one record per row (CsvRecord).
  std::string Csv() const;

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

// One CSV record (RFC 4180) ending in "\n": fields joined by commas, a field
// holding a comma, a double quote, CR or LF quoted, its quotes doubled.
std::string CsvRecord(const std::vector<std::string>& fields);

// A double for a CSV or table cell: up to 9 significant digits (exact for
// the 4-byte costs and round-trips a float), "inf", "-inf" or "nan".
std::string FormatNumber(double value);

// `message` in protobuf's canonical proto3 JSON, default values included so
// `"found": false` is visible to scripts: indented over several lines, or on
// one line (`one_line`) for streams that print one object per event. Ends
// with "\n". INTERNAL when protobuf cannot print it.
absl::StatusOr<std::string> MessageToJson(
    const google::protobuf::Message& message, bool one_line);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_OUTPUT_H_
