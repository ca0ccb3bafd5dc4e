// pathctl's output writers: the --output parser, aligned tables, CSV quoting
// and number formatting.
#include "client/pathctl/output.h"

#include <cmath>
#include <limits>

#include "gtest/gtest.h"
#include "pathd/v1/map_service.pb.h"

namespace pathd::pathctl {
namespace {

TEST(OutputFormatTest, ParsesTheThreeNamesAndRejectsOthers) {
  EXPECT_EQ(*ParseOutputFormat("table"), OutputFormat::kTable);
  EXPECT_EQ(*ParseOutputFormat("json"), OutputFormat::kJson);
  EXPECT_EQ(*ParseOutputFormat("csv"), OutputFormat::kCsv);
  const auto bad = ParseOutputFormat("xml");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("'xml'"), absl::string_view::npos);
  for (OutputFormat f :
       {OutputFormat::kTable, OutputFormat::kJson, OutputFormat::kCsv}) {
    EXPECT_EQ(*ParseOutputFormat(OutputFormatName(f)), f);
  }
}

TEST(OutputFormatTest, JsonIsAnAliasThatMustAgreeWithOutput) {
  EXPECT_EQ(*ResolveOutputFormat("", false), OutputFormat::kTable);
  EXPECT_EQ(*ResolveOutputFormat("", true), OutputFormat::kJson);
  EXPECT_EQ(*ResolveOutputFormat("json", true), OutputFormat::kJson);
  EXPECT_EQ(*ResolveOutputFormat("csv", false), OutputFormat::kCsv);
  EXPECT_EQ(ResolveOutputFormat("csv", true).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ResolveOutputFormat("yaml", false).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(TableTest, AlignsColumnsAndRightAlignsNumbers) {
  Table table({"NAME", "SIZE", "VERSION"});
  table.AddRow({"room", "10x10", "3"});
  table.AddRow({"a-much-longer-name", "512x512", "12"});
  EXPECT_EQ(table.Aligned(),
            "NAME                SIZE     VERSION\n"
            "room                10x10          3\n"
            "a-much-longer-name  512x512       12\n");
}

TEST(TableTest, HeaderOnlyTableHasNoTrailingSpaces) {
  Table table({"A", "LONGER"});
  EXPECT_EQ(table.Aligned(), "A  LONGER\n");
  EXPECT_EQ(table.Csv(), "A,LONGER\n");
}

TEST(TableTest, ShortRowsArePaddedToTheHeader) {
  Table table({"a", "b", "c"});
  table.AddRow({"1"});
  EXPECT_EQ(table.Csv(), "a,b,c\n1,,\n");
}

TEST(CsvTest, QuotesOnlyFieldsThatNeedIt) {
  EXPECT_EQ(CsvRecord({"plain", "1.5", ""}), "plain,1.5,\n");
  EXPECT_EQ(CsvRecord({"a,b"}), "\"a,b\"\n");
  EXPECT_EQ(CsvRecord({"say \"hi\""}), "\"say \"\"hi\"\"\"\n");
  EXPECT_EQ(CsvRecord({"two\nlines", "x"}), "\"two\nlines\",x\n");
  EXPECT_EQ(CsvRecord({"\"\"\""}), "\"\"\"\"\"\"\"\"\n");
}

TEST(CsvTest, TableCsvIsHeaderThenRows) {
  Table table({"x", "y", "note"});
  table.AddRow({"0", "0", "start"});
  table.AddRow({"1", "1", "goal, reached"});
  EXPECT_EQ(table.Csv(), "x,y,note\n0,0,start\n1,1,\"goal, reached\"\n");
}

TEST(FormatNumberTest, NineSignificantDigitsAndNamedSpecials) {
  EXPECT_EQ(FormatNumber(0), "0");
  EXPECT_EQ(FormatNumber(1234.5678), "1234.5678");
  EXPECT_EQ(FormatNumber(9.899494936611665), "9.89949494");
  EXPECT_EQ(FormatNumber(0.05), "0.05");
  EXPECT_EQ(FormatNumber(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(FormatNumber(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(FormatNumber(std::nan("")), "nan");
}

TEST(MessageToJsonTest, PrintsDefaultsOnOneLineOrIndented) {
  v1::MapInfo info;
  info.set_name("room");
  const auto one_line = MessageToJson(info, true);
  ASSERT_TRUE(one_line.ok()) << one_line.status();
  EXPECT_EQ(one_line->find('\n'), one_line->size() - 1) << *one_line;
  EXPECT_NE(one_line->find("\"name\":\"room\""), std::string::npos)
      << *one_line;
  // Defaults are printed, so a script sees "version": 0 rather than nothing.
  EXPECT_NE(one_line->find("\"version\""), std::string::npos) << *one_line;
  const auto indented = MessageToJson(info, false);
  ASSERT_TRUE(indented.ok());
  EXPECT_NE(indented->find("\n \"name\": \"room\""), std::string::npos)
      << *indented;
}

}  // namespace
}  // namespace pathd::pathctl
