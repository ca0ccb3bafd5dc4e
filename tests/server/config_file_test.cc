// The config file: YAML parsing into settings, applying them to Abseil flags
// with file:line errors, finding --config in argv as absl would, and the
// precedence command line > file > default.
#include "server/config_file.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/reflection.h"
#include "absl/time/time.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

ABSL_FLAG(int32_t, cfgtest_threads, 0, "test flag: an integer");
ABSL_FLAG(absl::Duration, cfgtest_grace, absl::Seconds(5),
          "test flag: a duration");
ABSL_FLAG(std::string, cfgtest_address, "default", "test flag: a string");
ABSL_FLAG(bool, cfgtest_verbose, false, "test flag: a boolean");
ABSL_FLAG(std::string, cfgtest_config, "", "test flag: names the config file");

namespace pathd::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// The flags the tests' config files may set; cfgtest_verbose and
// cfgtest_config exist but are not settable.
const std::vector<std::string> kSettable = {"cfgtest_threads", "cfgtest_grace",
                                            "cfgtest_address"};

MATCHER_P3(Setting, name, value, line, "") {
  return arg.name == name && arg.value == value && arg.line == line;
}

class ConfigFileTest : public ::testing::Test {
 protected:
  // Every test starts from the flags' defaults and leaves them there.
  absl::FlagSaver saver_;
};

TEST_F(ConfigFileTest, ParsesSettingsInFileOrderWithTheirLines) {
  const auto settings = ParseConfigYaml(
      "# pathd settings\n"
      "cfgtest_threads: 2\n"
      "\n"
      "cfgtest_address: 127.0.0.1:0   # host:port needs no quotes\n"
      "cfgtest_grace: 1m30s\n"
      "map_dir: \"\"\n",
      "pathd.yaml");
  ASSERT_TRUE(settings.ok()) << settings.status();
  EXPECT_THAT(*settings,
              ElementsAre(Setting("cfgtest_threads", "2", 2),
                          Setting("cfgtest_address", "127.0.0.1:0", 4),
                          Setting("cfgtest_grace", "1m30s", 5),
                          Setting("map_dir", "", 6)));
}

TEST_F(ConfigFileTest, EmptyOrCommentOnlyFileHasNoSettings) {
  for (const char* text : {"", "# nothing set\n"}) {
    const auto settings = ParseConfigYaml(text, "empty.yaml");
    ASSERT_TRUE(settings.ok()) << settings.status();
    EXPECT_TRUE(settings->empty());
  }
}

TEST_F(ConfigFileTest, MalformedFilesNameTheFileLineAndKey) {
  struct Case {
    std::string yaml;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"cfgtest_threads: 2\ncfgtest_grace: 1s\ncfgtest_threads: 3\n",
       "f.yaml:3: key 'cfgtest_threads': set twice in this file"},
      {"cfgtest_threads: [1, 2]\n",
       "f.yaml:1: key 'cfgtest_threads': must be a single value, not a list or "
       "mapping"},
      {"cfgtest_address:\n  host: x\n",
       "f.yaml:1: key 'cfgtest_address': must be a single value"},
      {"cfgtest_threads: 1\ncfgtest_address:\n",
       "f.yaml:2: key 'cfgtest_address': has no value (write \"\" for an empty "
       "string)"},
      {"- cfgtest_threads\n",
       "f.yaml:1: expected a YAML mapping of flag names to values"},
      {"just words\n", "f.yaml:1: expected a YAML mapping"},
      {"cfgtest_threads: 2\n  oops: [\n", "f.yaml:2: invalid YAML: "},
      {"[a, b]: 1\n", "f.yaml:1: keys must be flag names"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.yaml);
    const auto settings = ParseConfigYaml(c.yaml, "f.yaml");
    ASSERT_FALSE(settings.ok());
    EXPECT_EQ(settings.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(settings.status().message()), HasSubstr(c.message));
  }
}

TEST_F(ConfigFileTest, AppliesValuesThroughTheFlagsOwnParsers) {
  const std::vector<ConfigSetting> settings = {
      {"cfgtest_threads", "4", 1},
      {"cfgtest_grace", "250ms", 2},
      {"cfgtest_address", "10.0.0.1:9", 3}};
  ConfigOrigins origins;
  ASSERT_TRUE(
      ApplyConfigSettings(settings, "p.yaml", kSettable, &origins).ok());
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_threads), 4);
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_grace), absl::Milliseconds(250));
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_address), "10.0.0.1:9");
  EXPECT_EQ(origins.Of("cfgtest_grace"), "p.yaml:2");
  EXPECT_EQ(origins.Of("cfgtest_verbose"), "");
  // A value changed after the file (as the command line does) is no longer
  // the file's to answer for.
  absl::SetFlag(&FLAGS_cfgtest_threads, 5);
  EXPECT_EQ(origins.Of("cfgtest_threads"), "");
}

TEST_F(ConfigFileTest, BadValueCarriesTheFlagsOwnError) {
  const std::vector<ConfigSetting> settings = {{"cfgtest_threads", "3", 1},
                                               {"cfgtest_grace", "soon", 2}};
  const absl::Status status =
      ApplyConfigSettings(settings, "p.yaml", kSettable, nullptr);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(status.message(),
            "p.yaml:2: key 'cfgtest_grace': Illegal value 'soon' specified "
            "for flag 'cfgtest_grace'");
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_grace), absl::Seconds(5));
}

TEST_F(ConfigFileTest, UnknownOrUnsettableKeysAreRejected) {
  const auto Apply = [](const std::string& name) {
    const std::vector<ConfigSetting> settings = {{name, "1", 7}};
    return ApplyConfigSettings(settings, "p.yaml", kSettable, nullptr);
  };
  const absl::Status unknown = Apply("cfgtest_thread");
  EXPECT_EQ(unknown.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(unknown.message(),
            "p.yaml:7: key 'cfgtest_thread': not a pathd setting; valid keys: "
            "cfgtest_address, cfgtest_grace, cfgtest_threads");
  // Real flags outside the settable list: the file cannot reach them.
  EXPECT_THAT(std::string(Apply("cfgtest_verbose").message()),
              HasSubstr("key 'cfgtest_verbose': not a pathd setting"));
  EXPECT_THAT(std::string(Apply("help").message()),
              HasSubstr("key 'help': not a pathd setting"));
  EXPECT_THAT(std::string(Apply("--cfgtest_threads").message()),
              HasSubstr("(write flag names without dashes)"));
  EXPECT_EQ(Apply("config").message(),
            "p.yaml:7: key 'config': only the command line can name the "
            "config file");
  EXPECT_FALSE(absl::GetFlag(FLAGS_cfgtest_verbose));
}

TEST_F(ConfigFileTest, MissingFileIsNotFound) {
  const absl::Status status =
      LoadConfigFile("/nonexistent/pathd.yaml", kSettable, nullptr);
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("cannot read config file /nonexistent/pathd.yaml"));
}

std::string ValueIn(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  return FlagValueInArgv(argv, "cfgtest_config");
}

TEST_F(ConfigFileTest, FindsTheFlagInArgvAsAbslReadsIt) {
  EXPECT_EQ(ValueIn({"prog"}), "");
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_config=a.yaml"}), "a.yaml");
  EXPECT_EQ(ValueIn({"prog", "-cfgtest_config=a.yaml"}), "a.yaml");
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_config", "a.yaml"}), "a.yaml");
  EXPECT_EQ(
      ValueIn({"prog", "-cfgtest_config", "a.yaml", "--cfgtest_threads=2"}),
      "a.yaml");
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_config=a", "--cfgtest_config=b"}), "b");
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_config=a", "--cfgtest_config="}), "");
  EXPECT_EQ(ValueIn({"prog", "positional", "--cfgtest_config=a"}), "a");
  // After "--" everything is positional.
  EXPECT_EQ(ValueIn({"prog", "--", "--cfgtest_config=a"}), "");
  // "--string_flag VALUE": the next argument is that flag's value.
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_address", "--cfgtest_config=a"}), "");
  // A boolean flag takes no value from the next argument.
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_verbose", "--cfgtest_config=a"}), "a");
  // Missing value at the end: absl reports it; nothing to load here.
  EXPECT_EQ(ValueIn({"prog", "--cfgtest_config"}), "");
}

TEST_F(ConfigFileTest, HyphenatedFlagNamesReadAsUnderscores) {
  std::vector<std::string> args = {"prog", "--data-dir=/var/lib/pathd",
                                   "-log-level", "debug-ish", "--tls_cert",
                                   "a-b.pem", "-3", "--", "--not-a-flag"};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  // Values keep their hyphens, including one that looks like a short flag
  // but is a number, and nothing after "--" is touched.
  EXPECT_THAT(NormalizeFlagSpelling(argv),
              ElementsAre("prog", "--data_dir=/var/lib/pathd", "-log_level",
                          "debug-ish", "--tls_cert", "a-b.pem", "-3", "--",
                          "--not-a-flag"));
  const auto settings =
      ParseConfigYaml("cfgtest-threads: 2\ncfgtest_threads: 3\n", "x.yaml");
  ASSERT_FALSE(settings.ok());
  EXPECT_THAT(settings.status().message(), HasSubstr("set twice"));
  const auto hyphenated = ParseConfigYaml("cfgtest-threads: 2\n", "x.yaml");
  ASSERT_TRUE(hyphenated.ok()) << hyphenated.status();
  EXPECT_THAT(*hyphenated, ElementsAre(Setting("cfgtest_threads", "2", 1)));
}

// What pathd's main does: load the file named in argv, then parse the command
// line, whose flags override the file's; flags in neither keep their default.
TEST_F(ConfigFileTest, CommandLineOverridesFileOverridesDefault) {
  char dir_template[] = "/tmp/config_file_test_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string path = std::string(dir_template) + "/pathd.yaml";
  {
    std::ofstream out(path);
    out << "cfgtest_threads: 4\ncfgtest_grace: 2s\n";
  }
  std::vector<std::string> args = {
      "config_file_test", "--cfgtest_config=" + path, "--cfgtest_threads=7"};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());

  const std::string config_path = FlagValueInArgv(argv, "cfgtest_config");
  ASSERT_EQ(config_path, path);
  ConfigOrigins origins;
  ASSERT_TRUE(LoadConfigFile(config_path, kSettable, &origins).ok());
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_threads), 4);
  absl::ParseCommandLine(static_cast<int>(argv.size()), argv.data());

  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_threads), 7);  // command line
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_grace), absl::Seconds(2));  // file
  EXPECT_EQ(absl::GetFlag(FLAGS_cfgtest_address), "default");       // default
  EXPECT_EQ(origins.Of("cfgtest_threads"), "");
  EXPECT_EQ(origins.Of("cfgtest_grace"), path + ":2");
  std::remove(path.c_str());
  rmdir(dir_template);
}

}  // namespace
}  // namespace pathd::server
