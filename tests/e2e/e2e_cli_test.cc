// e2e_test: bash completion, render, maps import/export, TLS and tokens,
// help and version, and map name checks.
#include "tests/e2e/e2e_fixture.h"

namespace pathd::e2e_test {

// Runs `script` in bash after loading pathctl's completion script, with the
// helper `complete_line WORD...` printing the candidates for the last word.
ProcessResult RunCompletion(const std::string& completion_file,
                            const std::string& script) {
  const std::string program = absl::StrCat(
      "source '", completion_file, "'\n",
      "complete_line() {\n"
      "  COMP_WORDS=(\"$@\"); COMP_CWORD=$(( ${#COMP_WORDS[@]} - 1 )); COMPREPLY=()\n"
      "  _pathctl\n"
      "  echo \"${COMPREPLY[*]}\"\n"
      "}\n",
      script);
  return PathctlProcess({"--norc", "--noprofile", "-c", program}, {}, "/bin/bash")
      .Finish();
}

TEST_F(E2eTest, BashCompletionCompletesCommandsFlagsPlannersAndMapNames) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", OpenRoomMap(30, 5)));
  const ProcessResult generated = RunPathctl({"completion", "bash"});
  ASSERT_EQ(generated.exit_code, 0) << generated;
  const std::string file = MapFile("pathctl.bash", generated.out);
  const std::string ctl = PATHCTL_BIN;
  const std::string server = absl::StrCat("--server=", address_);
  const ProcessResult r = RunCompletion(
      file, absl::StrCat("complete_line ", ctl, " ''\n",
                         "complete_line ", ctl, " ma\n",
                         "complete_line ", ctl, " maps ''\n",
                         "complete_line ", ctl, " plan room 0 0 9 9 --plann\n",
                         "complete_line ", ctl, " plan room --planner dstar\n",
                         // Bash splits --flag=value at '='.
                         "complete_line ", ctl, " --output = c\n",
                         "complete_line ", ctl, " ", server, " maps get ''\n",
                         "complete_line ", ctl, " ", server, " --json plan h\n",
                         // An unreachable server completes no map names.
                         "complete_line ", ctl, " --server=127.0.0.1:1 plan ''\n",
                         "complete_line ", ctl, " completion ''\n"));
  ASSERT_EQ(r.exit_code, 0) << r;
  const std::vector<std::string> lines = absl::StrSplit(r.out, '\n');
  ASSERT_GE(lines.size(), 10u) << r;
  EXPECT_EQ(lines[0],
            "maps plan batch navigate cost-to-go check cache-stats sessions health metrics "
            "bench table nearest trip isochrone fleet simulate render completion help");
  EXPECT_EQ(lines[1], "maps");
  EXPECT_EQ(lines[2], "create list get delete set rect watch import export stats");
  EXPECT_EQ(lines[3], "--planner");
  EXPECT_EQ(lines[4], "dstar_lite");
  EXPECT_EQ(lines[5], "csv");
  std::vector<std::string> names = absl::StrSplit(lines[6], ' ');
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"hall", "room"})) << r;
  EXPECT_EQ(lines[7], "hall");
  EXPECT_EQ(lines[8], "");
  EXPECT_EQ(lines[9], "bash");
}

// The cell glyphs of `maps get --cells` output (the lines after the blank
// line that ends the map's info).
std::string CellsText(const ProcessResult& r) {
  const size_t blank = r.out.find("\n\n");
  return blank == std::string::npos ? "" : r.out.substr(blank + 2);
}

// pathctl render: a plan drawn into a PNG that decodes to the map's size at
// the default scale with the path, markers and expanded cells in their
// colours; the same as text; no path still draws the map and exits 3.
TEST_F(E2eTest, RenderDrawsAPlanAsPngAndAsText) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const std::string png = (temp_dir_ / "walled.png").string();
  const ProcessResult r = Ctl({"render", "walled", "--plan", "2", "2", "17",
                               "3", "--expansions", "-o", png});
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(absl::StrContains(
      r.out, absl::StrCat("wrote ", png, " (320x192 pixels, 16 per cell)\n")))
      << r;
  EXPECT_TRUE(absl::StrContains(r.out, "path (astar): ")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "expanded cells drawn")) << r;

  const absl::StatusOr<pathctl::Image> image =
      pathctl::DecodePngRgba(ReadFile(png), png, int64_t{1} << 24);
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 20 * 16);
  ASSERT_EQ(image->height, 12 * 16);
  const auto pixel = [&](int x, int y) {
    const size_t i = (static_cast<size_t>(y) * image->width + x) * 4;
    return pathctl::Rgb{image->pixels[i], image->pixels[i + 1],
                        image->pixels[i + 2]};
  };
  int64_t path_pixels = 0, expanded_pixels = 0;
  const pathctl::Rgb expanded_free = {255, 213, 128};
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x) {
      path_pixels += pixel(x, y) == pathctl::kPathColour;
      expanded_pixels += pixel(x, y) == expanded_free;
    }
  }
  EXPECT_GT(path_pixels, 16 * 15) << "the path spans at least 15 cells";
  EXPECT_GT(expanded_pixels, 0);
  EXPECT_EQ(pixel(2 * 16 + 8, 2 * 16 + 8), pathctl::kStartColour);
  EXPECT_EQ(pixel(17 * 16 + 8, 3 * 16 + 8), pathctl::kGoalColour);
  EXPECT_EQ(pixel(10 * 16, 0), pathctl::kLethalColour);  // the wall at (10,0)

  // Text: the same plan's cells, start and goal.
  const v1::PlanResponse plan = PlanJson({"walled", "2", "2", "17", "3"});
  const ProcessResult text =
      Ctl({"render", "walled", "2", "2", "17", "3", "--ascii"});
  ASSERT_EQ(text.exit_code, 0) << text;
  const std::vector<std::string> lines = absl::StrSplit(text.out, '\n');
  ASSERT_GE(lines.size(), 12u) << text;
  EXPECT_EQ(lines[2][2], 'S') << text;
  EXPECT_EQ(lines[3][17], 'G') << text;
  EXPECT_EQ(lines[0][10], '#') << text;
  int64_t stars = 0;
  for (int y = 0; y < 12; ++y)
    stars += std::count(lines[y].begin(), lines[y].end(), '*');
  EXPECT_EQ(stars, plan.path_size() - 2) << text;

  // The map alone, and a plan with no path: the map is still drawn.
  const ProcessResult map_only = Ctl({"render", "walled", "--ascii"});
  ASSERT_EQ(map_only.exit_code, 0) << map_only;
  EXPECT_TRUE(absl::StartsWith(map_only.out, "..........#.........\n"))
      << map_only;
  ASSERT_NO_FATAL_FAILURE(CreateMap("pocket", PocketRoomMap()));
  const std::string pocket_png = (temp_dir_ / "pocket.png").string();
  const ProcessResult none = Ctl(
      {"render", "pocket", "--plan", "2", "2", "18", "0", "-o", pocket_png});
  EXPECT_EQ(none.exit_code, 3) << none;
  EXPECT_TRUE(absl::StrContains(none.out, "no path (astar): NO_PATH")) << none;
  EXPECT_TRUE(fs::exists(pocket_png));

  // Usage errors exit 2; a missing map is the server's NOT_FOUND.
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{
           {"render", "walled"},
           {"render", "walled", "--plan", "--ascii"},
           {"render", "walled", "--expansions", "--ascii"},
           {"render", "walled", "-o", "walled.jpg"},
           {"render", "walled", "--ascii", "-o", png, "--scale", "65"},
           {"render", "walled", "2", "2", "17", "--ascii"},
           {"render", "walled", "2", "2", "17", "3", "--ascii",
            "--planner=nope"}}) {
    EXPECT_EQ(Ctl(args).exit_code, 2) << absl::StrJoin(args, " ");
  }
  ExpectRpcError({"render", "nope", "--ascii"}, "NOT_FOUND", {"nope"});
}

// render --inflation_radius draws the grid the planners see: Nav2's costs
// around the corridor's walls in shades (text glyphs and PNG greys of the
// cost each row gets), the plain map without it.
TEST_F(E2eTest, RenderDrawsTheInflationGradient) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("corridor", CorridorMap(), {"--resolution=0.05"}));
  const ProcessResult plain = Ctl({"render", "corridor", "--ascii"});
  ASSERT_EQ(plain.exit_code, 0) << plain;
  EXPECT_TRUE(absl::StrContains(plain.out, "\n" + std::string(40, '.') + "\n")) << plain;
  const ProcessResult text =
      Ctl({"render", "corridor", "--ascii", "--inflation_radius=0.55"});
  ASSERT_EQ(text.exit_code, 0) << text;
  const std::vector<std::string> lines = absl::StrSplit(text.out, '\n');
  ASSERT_GE(lines.size(), 11u) << text;
  // Rows 1..5 are 1..5 cells from the nearest wall: 252 * e^(-d / 2) is 152,
  // 92, 55, 34, 20, drawn '1' + (cost - 1) / 28.
  const char want[] = {'#', '6', '4', '2', '2', '1', '2', '2', '4', '6', '#'};
  for (int y = 0; y < 11; ++y) {
    EXPECT_EQ(lines[y], std::string(40, want[y])) << "row " << y << "\n" << text;
  }
  const std::string png = (temp_dir_ / "corridor.png").string();
  const ProcessResult picture = Ctl({"render", "corridor", "-o", png, "--scale=1",
                                     "--inflation_radius_cells=11"});
  ASSERT_EQ(picture.exit_code, 0) << picture;
  const absl::StatusOr<pathctl::Image> image =
      pathctl::DecodePngRgba(ReadFile(png), png, int64_t{1} << 24);
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 40);
  const auto pixel = [&](int x, int y) {
    const size_t i = (static_cast<size_t>(y) * image->width + x) * 4;
    return pathctl::Rgb{image->pixels[i], image->pixels[i + 1], image->pixels[i + 2]};
  };
  EXPECT_EQ(pixel(20, 1), pathctl::CostColour(152));
  EXPECT_EQ(pixel(20, 5), pathctl::CostColour(20));
  EXPECT_EQ(pixel(20, 9), pathctl::CostColour(152));
  EXPECT_EQ(pixel(20, 0), pathctl::kLethalColour);
  // A bad value is refused before anything is drawn.
  const ProcessResult bad =
      Ctl({"render", "corridor", "--ascii", "--inflation_radius=-1"});
  EXPECT_EQ(bad.exit_code, 2) << bad;
  EXPECT_TRUE(absl::StrContains(bad.err, "inflation radius")) << bad;
}

// maps import / export through the server: the bundled ROS map exported as
// YAML + PGM and imported again has the same cells; as a .map its unknown
// cells become blocked (with a warning); a PNG occupancy image imports with
// map_server's thresholds.
TEST_F(E2eTest, MapsImportAndExportRoundTrip) {
  const std::string warehouse =
      absl::StrCat(PATHD_SOURCE_DIR, "/maps/warehouse.yaml");
  const ProcessResult imported = Ctl({"maps", "import", "wh", warehouse});
  ASSERT_EQ(imported.exit_code, 0) << imported;
  EXPECT_TRUE(absl::StartsWith(imported.out, "created map wh from "))
      << imported;
  const std::string original = CellsText(Ctl({"maps", "get", "wh", "--cells"}));
  ASSERT_FALSE(original.empty());

  const std::string yaml = (temp_dir_ / "out" / "wh.yaml").string();
  fs::create_directories(temp_dir_ / "out");
  const ProcessResult exported = Ctl({"maps", "export", "wh", yaml});
  ASSERT_EQ(exported.exit_code, 0) << exported;
  EXPECT_EQ(exported.err, "") << exported;
  EXPECT_TRUE(fs::exists(temp_dir_ / "out" / "wh.pgm"));
  ASSERT_EQ(Ctl({"maps", "import", "wh_yaml", yaml}).exit_code, 0);
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "wh_yaml", "--cells"})), original);
  const auto info = ParseJson<v1::GetMapResponse>(
                        Ctl({"maps", "get", "wh_yaml", "--json"}).out)
                        .info();
  EXPECT_DOUBLE_EQ(info.resolution(), 0.1);
  EXPECT_DOUBLE_EQ(info.origin().x(), -3.0);
  EXPECT_DOUBLE_EQ(info.origin().y(), -2.0);

  const std::string map = (temp_dir_ / "out" / "wh.map").string();
  const ProcessResult as_map = Ctl({"maps", "export", "wh", map});
  ASSERT_EQ(as_map.exit_code, 0) << as_map;
  EXPECT_TRUE(absl::StrContains(as_map.err, "unknown (255) written as 'O'"))
      << as_map;
  ASSERT_EQ(Ctl({"maps", "import", "wh_map", map}).exit_code, 0);
  std::string blocked = original;
  std::replace(blocked.begin(), blocked.end(), '?', '#');
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "wh_map", "--cells"})), blocked);

  // A picture of the map at one pixel per cell, rows as map_server's, is an
  // occupancy image of the same cells.
  const std::string picture_png = (temp_dir_ / "out" / "wh_map.png").string();
  ASSERT_EQ(
      Ctl({"render", "wh", "--scale=1", "--y_up", "-o", picture_png}).exit_code,
      0);
  ASSERT_EQ(Ctl({"maps", "import", "wh_png", picture_png}).exit_code, 0);
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "wh_png", "--cells"})), original);

  // A weighted cell is written as passable, and said so.
  ASSERT_EQ(Ctl({"maps", "set", "wh", "5", "5", "100"}).exit_code, 0);
  const ProcessResult weighted = Ctl({"maps", "export", "wh", yaml});
  ASSERT_EQ(weighted.exit_code, 0) << weighted;
  EXPECT_TRUE(absl::StrContains(weighted.err, "warning: 1 cell of cost 1..252"))
      << weighted;

  // A 3x2 PNG: black, white, grey (205) over white, white, black.
  pathctl::Image picture;
  picture.width = 3;
  picture.height = 2;
  picture.pixels = {0,   0,   0,   255, 255, 255, 205, 205, 205,
                    255, 255, 255, 255, 255, 255, 0,   0,   0};
  const std::string png = (temp_dir_ / "room.png").string();
  ASSERT_TRUE(pathctl::WritePngFile(picture, png).ok());
  const ProcessResult from_png =
      Ctl({"maps", "import", "room", png, "--resolution", "0.5", "--json"});
  ASSERT_EQ(from_png.exit_code, 0) << from_png;
  EXPECT_DOUBLE_EQ(
      ParseJson<v1::CreateMapResponse>(from_png.out).info().resolution(), 0.5);
  // Row 0 is the image's bottom row.
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "room", "--cells"})), "..#\n#.?\n");
  ASSERT_EQ(
      Ctl({"maps", "import", "room", png, "--replace", "--negate"}).exit_code,
      0);
  // Negated, grey 205 is p = 0.80: occupied.
  EXPECT_EQ(CellsText(Ctl({"maps", "get", "room", "--cells"})), "##.\n.##\n");

  EXPECT_EQ(
      Ctl({"maps", "import", "x", map, "--occupied_thresh=0.5"}).exit_code, 2);
  EXPECT_EQ(Ctl({"maps", "import", "x", yaml, "--resolution=2"}).exit_code, 2);
  EXPECT_EQ(Ctl({"maps", "import", "x", png, "--free_thresh=0.7"}).exit_code,
            2);
  EXPECT_EQ(Ctl({"maps", "import", "x", "room.bmp"}).exit_code, 2);
  EXPECT_EQ(Ctl({"maps", "export", "wh", "wh.png"}).exit_code, 2);
  ExpectRpcError({"maps", "import", "x", (temp_dir_ / "missing.png").string()},
                 "NOT_FOUND", {"missing.png"});
  ExpectRpcError({"maps", "export", "nope", yaml}, "NOT_FOUND", {"nope"});
}

// A map file over one default-sized message (4 MiB) is parsed by pathctl
// and streamed (UploadMap); export reads it back through DownloadMap, and a
// map longer than 4096 cells renders downsampled.
TEST_F(E2eTest, MapsOverOneMessageAreStreamedBothWays) {
  constexpr int kW = 5000, kH = 900;  // 4.5 MB of Moving AI text
  std::string text = absl::StrCat("type octile\nheight ", kH, "\nwidth ", kW, "\nmap\n");
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) text.push_back((x * 7 + y * 3) % 11 == 0 ? '@' : '.');
    text.push_back('\n');
  }
  fs::create_directories(temp_dir_ / "out");
  const std::string file = (temp_dir_ / "big.map").string();
  e2e::WriteFile(file, text);
  const ProcessResult imported = Ctl({"maps", "import", "big", file});
  ASSERT_EQ(imported.exit_code, 0) << imported;
  EXPECT_TRUE(absl::StartsWith(imported.out, "created map big from ")) << imported;
  const ProcessResult created = Ctl({"maps", "create", "big2", "--from", file});
  ASSERT_EQ(created.exit_code, 0) << created;

  const std::string exported = (temp_dir_ / "out" / "big.map").string();
  const ProcessResult out = Ctl({"maps", "export", "big2", exported});
  ASSERT_EQ(out.exit_code, 0) << out;
  EXPECT_TRUE(e2e::ReadFile(exported) == text) << "the exported map differs";

  const std::string png = (temp_dir_ / "out" / "big.png").string();
  const ProcessResult drawn = Ctl({"render", "big", "-o", png});
  ASSERT_EQ(drawn.exit_code, 0) << drawn;
  EXPECT_TRUE(absl::StrContains(drawn.out, "(2500x450 pixels, one per 2x2 cells"))
      << drawn;
}

// pathd with TLS and --auth_tokens, driven by pathctl with --tls_ca and
// --token_file / $PATHD_TOKEN; the daemon's whole log (trace level) is
// captured and must not contain a token.
TEST_F(E2eTest, TlsAndTokensThroughPathctl) {
  const fs::path cert_dir = temp_dir_ / "certs";
  fs::create_directory(cert_dir);
  testing::TestCerts certs;
  ASSERT_TRUE(testing::MakeTestCerts(cert_dir, &certs))
      << "the openssl tool failed (is Debian's openssl package installed?)";
  const std::string read_token(64, 'r');
  const std::string write_token = "w0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcd";
  const fs::path tokens = temp_dir_ / "tokens.yaml";
  WriteFile(tokens, absl::StrCat("tokens:\n  - {name: robot-7, role: read, token: ",
                                 read_token, "}\n  - {name: mapper, role: write, token: ",
                                 write_token, "}\n"));
  fs::permissions(tokens, fs::perms::owner_read | fs::perms::owner_write);
  const fs::path read_file = temp_dir_ / "read.token";
  const fs::path write_file = temp_dir_ / "write.token";
  WriteFile(read_file, read_token + "\n");
  WriteFile(write_file, write_token + "\n");

  const std::unique_ptr<e2e::PathdProcess> daemon = StartOwnPathd(
      {"--tls_cert=" + certs.server_cert, "--tls_key=" + certs.server_key,
       "--auth_tokens=" + tokens.string(), "--log_level=trace"});
  ASSERT_TRUE(daemon->listening());
  const std::string server = "--server=" + daemon->address();
  const std::string tls = "--tls_ca=" + certs.ca;

  const std::string map = MapFile("room.map", OpenRoomMap());
  ProcessResult r = RunPathctl({server, tls, "--token_file=" + write_file.string(),
                                "maps", "create", "room", "--from", map});
  ASSERT_EQ(r.exit_code, 0) << r;
  r = RunPathctl({server, tls, "--token_file=" + read_file.string(), "plan", "room",
                  "0", "0", "9", "9"});
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.err, "") << r;
  r = RunPathctl({server, tls, "--token_file=" + read_file.string(), "maps", "set",
                  "room", "5", "5", "lethal"});
  EXPECT_EQ(r.exit_code, 8) << r;
  EXPECT_EQ(r.err,
            "error: PERMISSION_DENIED: token 'robot-7' has role read; "
            "/pathd.v1.MapService/UpdateMap needs role write\n");
  // The token from the environment.
  r = RunPathctl({server, tls, "maps", "set", "room", "5", "5", "lethal"},
                 {"PATHD_TOKEN=" + write_token});
  EXPECT_EQ(r.exit_code, 0) << r;
  r = RunPathctl({server, tls, "maps", "list"});
  EXPECT_EQ(r.exit_code, 8) << r;
  EXPECT_TRUE(absl::StartsWith(r.err, "error: UNAUTHENTICATED: missing")) << r;
  r = RunPathctl({server, tls, "--token=" + std::string(64, 'x'), "maps", "list"});
  EXPECT_EQ(r.err, "error: UNAUTHENTICATED: unknown token\n") << r;
  // Health needs no token; plaintext cannot reach a TLS server.
  r = RunPathctl({server, tls, "health"});
  EXPECT_EQ(r.out, "SERVING\n") << r;
  r = RunPathctl({server, "--token_file=" + read_file.string(), "health"});
  EXPECT_EQ(r.exit_code, 5) << r;
  EXPECT_TRUE(absl::StartsWith(r.err, "error: UNAVAILABLE")) << r;
  // gRPC only says "Socket closed"; pathctl suggests what is missing.
  EXPECT_TRUE(absl::StrContains(r.err, "\nhint: ")) << r;
  EXPECT_TRUE(absl::StrContains(r.err, "give --tls_ca FILE")) << r;
  // Flag mistakes are usage errors.
  r = RunPathctl({server, tls, "--tls_cert=" + certs.client_cert, "health"});
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(absl::StrContains(r.err, "--tls_cert and --tls_key must be given together"))
      << r;
  r = RunPathctl({server, "--token_file=" + (temp_dir_ / "none").string(), "health"});
  EXPECT_EQ(r.exit_code, 7) << r;
  EXPECT_TRUE(absl::StrContains(r.err, "--token_file: cannot open")) << r;

  const ProcessResult log = StopOwnPathd(*daemon);
  EXPECT_EQ(log.exit_code, 0) << log;
  EXPECT_TRUE(absl::StrContains(log.err, "transport: TLS; authentication: bearer tokens"))
      << log.err;
  EXPECT_TRUE(absl::StrContains(log.err, "refused UpdateMap")) << log.err;
  EXPECT_TRUE(absl::StrContains(log.err, "rpc=UpdateMap map=room")) << log.err;
  for (const std::string& token : {read_token, write_token}) {
    EXPECT_FALSE(absl::StrContains(log.err, token)) << "a token is in pathd's log";
  }
}

// pathctl help CMD, CMD --help and --version: generated from the command
// table, with the flags the command reads.
TEST_F(E2eTest, HelpForOneCommandAndVersion) {
  const ProcessResult help = RunPathctl({"help", "maps", "rect"});
  EXPECT_EQ(help.exit_code, 0) << help;
  EXPECT_TRUE(absl::StartsWith(
      help.out, "usage: pathctl [flags] maps rect NAME X0 Y0 X1 Y1 COST"))
      << help;
  EXPECT_TRUE(absl::StrContains(help.out, "--expected_version")) << help;
  EXPECT_FALSE(absl::StrContains(help.out, "--planner")) << help;
  const ProcessResult same = RunPathctl({"maps", "rect", "--help"});
  EXPECT_EQ(same.exit_code, 0) << same;
  EXPECT_EQ(same.out, help.out);
  const ProcessResult group = RunPathctl({"help", "maps"});
  EXPECT_EQ(group.exit_code, 0) << group;
  EXPECT_TRUE(absl::StrContains(group.out, "maps watch NAME")) << group;
  const ProcessResult unknown = RunPathctl({"help", "frobnicate"});
  EXPECT_EQ(unknown.exit_code, 2) << unknown;
  EXPECT_TRUE(absl::StrContains(unknown.err, "unknown command 'frobnicate'")) << unknown;
  const ProcessResult version = RunPathctl({"--version"});
  EXPECT_EQ(version.exit_code, 0) << version;
  EXPECT_TRUE(absl::StartsWith(version.out, "pathctl ")) << version;
  EXPECT_TRUE(absl::StrContains(version.out, ".")) << version;
}

// Regression (a 100 KiB name failed with gRPC's metadata-size error): map
// names are checked in pathctl by the server's rule and message before they
// go into the routing header; the server never sees the call.
TEST_F(E2eTest, MapNamesAreCheckedBeforeTheHeader) {
  const std::string map = MapFile("room.map", OpenRoomMap());
  const ProcessResult huge =
      Ctl({"maps", "create", std::string(100 * 1024, 'a'), "--from", map});
  EXPECT_EQ(huge.exit_code, 1) << huge.err.substr(0, 300);
  EXPECT_EQ(huge.err,
            "error: INVALID_ARGUMENT: map name is 102400 characters long; the "
            "limit is 128\n");
  const ProcessResult slash = Ctl({"plan", "a/b", "0", "0", "1", "1"});
  EXPECT_EQ(slash.exit_code, 1) << slash;
  EXPECT_TRUE(absl::StartsWith(
      slash.err, "error: INVALID_ARGUMENT: map name 'a/b' has character 0x2f"))
      << slash;
  const ProcessResult batch =
      Ctl({"batch", MapFile("bad.txt", "q1 .hidden 0 0 1 1\n")});
  EXPECT_EQ(batch.exit_code, 2) << batch;
  EXPECT_TRUE(absl::StrContains(batch.err, "must not start with '.'")) << batch;
}

// Regression: maps rect swapped inverted corners that the API refuses; now it
// refuses them with the server's message and the map keeps its version.
TEST_F(E2eTest, MapsRectRefusesInvertedCorners) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult r = Ctl({"maps", "rect", "room", "9", "5", "0", "5", "lethal"});
  EXPECT_EQ(r.exit_code, 1) << r;
  EXPECT_EQ(r.err, "error: INVALID_ARGUMENT: change 0: rect (9, 5)-(0, 5) has min > max\n");
  const ProcessResult info = Ctl({"maps", "get", "room", "--output=csv"});
  EXPECT_TRUE(absl::StrContains(info.out, ",1,100,0\n")) << info;  // version 1
}

// Regression: a missing export folder was reported as PERMISSION_DENIED.
TEST_F(E2eTest, ExportToAMissingFolderIsNotFoundNamingIt) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const std::string folder = (temp_dir_ / "no" / "such" / "dir").string();
  ExpectRpcError({"maps", "export", "room", folder + "/x.map"}, "NOT_FOUND",
                 {"folder " + folder + " does not exist"});
}

}  // namespace pathd::e2e_test
