// The command table and what is generated from it (client/pathctl/command.h):
// dispatch, the flag check, short usage on a usage error, help, and the
// checks Run makes before any call. No server: every case here ends before
// a command connects (the address is a closed port, so a call would fail
// UNAVAILABLE, which no case expects).
#include "client/pathctl/command.h"

#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

struct Result {
  int code;
  std::string out;
  std::string err;
};

Result RunWith(Options options, const std::vector<std::string>& args) {
  options.global.server = "127.0.0.1:1";
  std::ostringstream out;
  std::ostringstream err;
  const int code = Run(options, args, out, err);
  return {code, out.str(), err.str()};
}

Result RunArgs(const std::vector<std::string>& args) { return RunWith(Options(), args); }

TEST(CommandTableTest, EveryCommandIsCompleteAndFindable) {
  std::set<std::string> names;
  for (const Command* c : Commands()) {
    SCOPED_TRACE(std::string(c->name));
    EXPECT_TRUE(names.insert(std::string(c->name)).second) << "listed twice";
    EXPECT_NE(c->run, nullptr);
    EXPECT_FALSE(c->help.empty());
    EXPECT_EQ(FindCommand(c->name), c);
    std::set<std::string> flags;
    for (absl::string_view flag : c->flags) {
      EXPECT_TRUE(flags.insert(std::string(flag)).second) << flag << " listed twice";
      for (absl::string_view global : kGlobalFlags) EXPECT_NE(flag, global);
    }
  }
  EXPECT_EQ(FindCommand("maps"), nullptr);
  EXPECT_EQ(CommandsOfGroup("maps").size(), 10u);
}

// Every flag a command reads is explained in --help.
TEST(CommandTableTest, EveryFlagIsDocumented) {
  const std::string usage = UsageText();
  for (const Command* c : Commands()) {
    for (absl::string_view flag : c->flags) {
      const std::string spelled = absl::StrCat(flag.size() == 1 ? "-" : "--", flag);
      EXPECT_TRUE(absl::StrContains(usage, spelled)) << spelled << " of " << c->name;
    }
  }
}

TEST(RunTest, UnknownAndMissingCommandsListTheCommands) {
  Result r = RunArgs({});
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_TRUE(absl::StartsWith(r.err, "error: missing command\n\nusage:\n")) << r.err;
  r = RunArgs({"frobnicate"});
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_TRUE(absl::StrContains(
      r.err,
      "unknown command 'frobnicate'; expected maps, plan, batch, navigate, cost-to-go, "
      "check, cache-stats, sessions, health, metrics, bench, table, nearest, trip, isochrone, fleet, simulate, "
      "render, completion, help"))
      << r.err;
  r = RunArgs({"maps", "shred"});
  EXPECT_TRUE(absl::StrContains(r.err, "unknown maps subcommand 'shred'; expected "
                                       "create, list, get, delete, set, rect, watch, "
                                       "import, export"))
      << r.err;
  EXPECT_TRUE(absl::StrContains(r.err, "usage: pathctl [flags] maps create")) << r.err;
  EXPECT_FALSE(absl::StrContains(r.err, " plan NAME")) << r.err;
}

// Regression: `plan ... -o x.png` silently wrote nothing.
TEST(RunTest, AFlagTheCommandDoesNotReadIsAUsageError) {
  Options options;
  options.given_flags = {"o"};
  Result r = RunWith(options, {"plan", "room", "0", "0", "1", "1"});
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_TRUE(absl::StartsWith(r.err, "error: -o does not apply to plan; simulate, render read it\n"))
      << r.err;
  options.given_flags = {"server", "json", "cells"};
  r = RunWith(options, {"maps", "list"});
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_TRUE(absl::StartsWith(r.err, "error: --cells does not apply to maps list; maps "
                                      "get reads it\n"))
      << r.err;
  // Global flags apply everywhere, a command's own flags to it.
  options.given_flags = {"server", "timeout", "output", "count"};
  r = RunWith(options, {"maps", "watch", "room", "extra"});
  EXPECT_TRUE(absl::StartsWith(r.err, "error: maps watch takes one NAME")) << r.err;
}

TEST(RunTest, AUsageErrorShowsTheCommandsOwnUsage) {
  const Result r = RunArgs({"plan", "room", "0", "0"});
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_EQ(r.err, absl::StrCat("error: plan takes NAME SX SY GX GY\n\n",
                                ShortUsage(*FindCommand("plan"))));
  EXPECT_TRUE(absl::StartsWith(ShortUsage(*FindCommand("plan")),
                               "usage: pathctl [flags] plan NAME SX SY GX GY"));
  EXPECT_TRUE(absl::EndsWith(ShortUsage(*FindCommand("plan")),
                             "run 'pathctl help plan' for details\n"));
}

// Regression: a 100 KiB name failed in gRPC's metadata limit; the rule is
// now checked before any call, for every command that takes a map name.
TEST(RunTest, MapNamesAreCheckedBeforeAnyCall) {
  for (const Command* c : Commands()) {
    if (c->map_arg == MapArg::kNone) continue;
    SCOPED_TRACE(std::string(c->name));
    std::vector<std::string> args = absl::StrSplit(c->name, ' ');
    args.push_back(std::string(100 * 1024, 'a'));
    const Result r = RunArgs(args);
    EXPECT_EQ(r.code, kExitError);
    EXPECT_EQ(r.err,
              "error: INVALID_ARGUMENT: map name is 102400 characters long; the limit "
              "is 128\n");
  }
}

TEST(RunTest, HelpPrintsOneCommandOrAGroup) {
  Result r = RunArgs({"help", "maps", "rect"});
  EXPECT_EQ(r.code, kExitOk);
  EXPECT_EQ(r.out, CommandHelp(*FindCommand("maps rect")));
  EXPECT_TRUE(absl::StrContains(r.out, "--expected_version")) << r.out;
  r = RunArgs({"help", "maps"});
  EXPECT_EQ(r.code, kExitOk);
  EXPECT_TRUE(absl::StrContains(r.out, "maps import NAME FILE")) << r.out;
  r = RunArgs({"help"});
  EXPECT_EQ(r.out, UsageText());
  EXPECT_TRUE(absl::StrContains(VersionText(), "pathctl "));
}

TEST(CommandEnvTest, PlaintextCallClosedByATlsPortGetsAHint) {
  Options options;
  options.global.server = "host:1";
  std::ostringstream out;
  std::ostringstream err;
  CommandEnv env(options, out, err);
  const absl::Status closed = absl::UnavailableError(
      "failed to connect to all addresses; last error: UNAVAILABLE: "
      "ipv4:127.0.0.1:1: Socket closed");
  EXPECT_EQ(env.Fail(closed), kExitUnavailable);
  EXPECT_TRUE(absl::StrContains(err.str(), "\nhint: host:1 closed a plaintext "
                                           "connection; if it serves TLS, give "
                                           "--tls_ca FILE"))
      << err.str();
  // A refused connection is a stopped server, not TLS; with --tls_ca given
  // the hint would be wrong.
  err.str("");
  env.Fail(absl::UnavailableError("ipv4:127.0.0.1:1: Connection refused"));
  EXPECT_FALSE(absl::StrContains(err.str(), "hint:")) << err.str();
  options.global.credentials.tls_ca = "ca.pem";
  err.str("");
  env.Fail(closed);
  EXPECT_FALSE(absl::StrContains(err.str(), "hint:")) << err.str();
}

}  // namespace
}  // namespace pathd::pathctl
