// bad_input_test's MapService rows: CreateMap dimensions, cell arrays, poses,
// Moving AI and ROS sources and --map_dir files; answers larger than one
// message; UpdateMap changes.
#include "tests/e2e/bad_input_fixture.h"

namespace pathd::bad_input_test {

void BadInputTest::AddMapCases(std::vector<Case>& cases) {
  // ---- CreateMap: dimensions, cell arrays, poses, sources ----
  const auto create = [&](const std::string& what, v1::CreateMapRequest request,
                          StatusCode code, const std::string& message) {
    cases.push_back({"CreateMap", what,
                     [=, this] { return CreateMap(request); }, code, message});
  };
  create("negative width", RawMap("m", -1, 4, 4), StatusCode::INVALID_ARGUMENT,
         "width -1 and height 4 must be positive");
  create("zero height", RawMap("m", 4, 0, 0), StatusCode::INVALID_ARGUMENT,
         "must be positive");
  create("INT32_MIN dimensions", RawMap("m", kIntMin, kIntMin, 0),
         StatusCode::INVALID_ARGUMENT, "must be positive");
  create("width * height overflowing int32", RawMap("m", kIntMax, kIntMax, 4),
         StatusCode::RESOURCE_EXHAUSTED, "--max_map_cells");
  create("65536 x 65536 without cells", RawMap("m", 65536, 65536, 0),
         StatusCode::RESOURCE_EXHAUSTED, "--max_map_cells");
  create("width over the grid limit", RawMap("m", 65537, 1, 65537),
         StatusCode::INVALID_ARGUMENT, "width 65537 is out of range");
  create("too few cells", RawMap("m", 2, 2, 3), StatusCode::INVALID_ARGUMENT,
         "needs 4 cells, got 3");
  create("too many cells", RawMap("m", 2, 2, 5), StatusCode::INVALID_ARGUMENT,
         "needs 4 cells, got 5");
  create("no cells", RawMap("m", 2, 2, 0), StatusCode::INVALID_ARGUMENT,
         "needs 4 cells, got 0");
  {
    v1::CreateMapRequest none;
    none.set_name("m");
    create("no source", none, StatusCode::INVALID_ARGUMENT,
           "source is not set");
  }
  for (const auto& [what, resolution] :
       std::vector<std::pair<std::string, double>>{
           {"NaN resolution", kNaN},
           {"infinite resolution", kInf},
           {"negative resolution", -0.5}}) {
    v1::CreateMapRequest request = RawMap("m", 2, 2, 4);
    request.set_resolution(resolution);
    create(what, request, StatusCode::INVALID_ARGUMENT, "resolution");
  }
  for (const auto& [what, field, value] :
       std::vector<std::tuple<std::string, std::string, double>>{
           {"NaN origin.x", "origin.x", kNaN},
           {"infinite origin.y", "origin.y", -kInf},
           {"NaN origin.yaw", "origin.yaw", kNaN}}) {
    v1::CreateMapRequest request = RawMap("m", 2, 2, 4);
    v1::Origin* origin = request.mutable_origin();
    if (field == "origin.x") origin->set_x(value);
    if (field == "origin.y") origin->set_y(value);
    if (field == "origin.yaw") origin->set_yaw(value);
    create(what, request, StatusCode::INVALID_ARGUMENT, field);
  }
  {
    v1::CreateMapRequest exists = RawMap("room", 2, 2, 4);
    create("existing name without replace", exists, StatusCode::ALREADY_EXISTS,
           "map 'room' already exists");
  }
  // Moving AI text.
  const auto movingai = [&](const std::string& what, const std::string& text,
                            StatusCode code, const std::string& message) {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.set_movingai_text(text);
    create(what, request, code, message);
  };
  movingai("empty Moving AI text", "", StatusCode::INVALID_ARGUMENT,
           "movingai_text");
  movingai("Moving AI garbage", "\x01\x02 garbage\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  movingai("negative Moving AI height",
           "type octile\nheight -3\nwidth 4\nmap\n",
           StatusCode::INVALID_ARGUMENT, "height");
  movingai("Moving AI height beyond int64",
           "type octile\nheight 1e99\nwidth 4\nmap\n",
           StatusCode::INVALID_ARGUMENT, "height");
  movingai("Moving AI 65536 x 65536",
           "type octile\nheight 65536\nwidth 65536\nmap\n",
           StatusCode::RESOURCE_EXHAUSTED,
           "65536 = 4294967296 cells exceeds the limit of 2097152 cells "
           "(--max_map_cells)");
  movingai("Moving AI short row",
           "type octile\nheight 2\nwidth 3\nmap\n...\n..\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  movingai("Moving AI missing rows",
           "type octile\nheight 3\nwidth 3\nmap\n...\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  movingai("Moving AI unknown terrain",
           "type octile\nheight 1\nwidth 2\nmap\n.\x7f\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  // ROS map_server YAML + PGM.
  const auto ros = [&](const std::string& what, const std::string& yaml,
                       const std::string& pgm, StatusCode code,
                       const std::string& message) {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.mutable_ros_map()->set_yaml(yaml);
    request.mutable_ros_map()->set_image(pgm);
    create(what, request, code, message);
  };
  const std::string good_yaml =
      "image: x.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  const std::string good_pgm =
      std::string("P5\n2 2\n255\n") + std::string(4, '\xfe');
  ros("empty YAML", "", good_pgm, StatusCode::INVALID_ARGUMENT, "ros_map.yaml");
  ros("YAML garbage", "{{{{ ::: ]]", good_pgm, StatusCode::INVALID_ARGUMENT,
      "ros_map.yaml");
  ros("YAML nested 100000 deep", std::string(100000, '['), good_pgm,
      StatusCode::INVALID_ARGUMENT, "ros_map.yaml");
  ros("YAML with NUL", std::string("image: x\0\nresolution: 1\n", 24), good_pgm,
      StatusCode::INVALID_ARGUMENT, "ros_map.yaml");
  ros("YAML NaN resolution",
      "image: x.pgm\nresolution: .nan\norigin: [0, 0, 0]\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "resolution");
  ros("YAML zero resolution",
      "image: x.pgm\nresolution: 0\norigin: [0, 0, 0]\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "resolution");
  ros("YAML infinite origin",
      "image: x.pgm\nresolution: 1\norigin: [0, -.inf, 0]\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "origin");
  ros("YAML string origin", "image: x.pgm\nresolution: 1\norigin: [a, b, c]\n",
      good_pgm, StatusCode::INVALID_ARGUMENT, "origin");
  ros("YAML negate 7", good_yaml + "negate: 7\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "negate");
  ros("YAML thresholds crossed",
      good_yaml + "occupied_thresh: 0.1\nfree_thresh: 0.9\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "thresh");
  ros("YAML unknown mode", good_yaml + "mode: sideways\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "mode");
  ros("empty PGM", good_yaml, "", StatusCode::INVALID_ARGUMENT,
      "ros_map.image");
  ros("PGM garbage", good_yaml, "P9 \x01\x02", StatusCode::INVALID_ARGUMENT,
      "ros_map.image");
  ros("PGM negative width", good_yaml, "P5\n-2 2\n255\n\x01\x01\x01\x01",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM 65536 x 65536", good_yaml, "P5\n65536 65536\n255\n",
      StatusCode::RESOURCE_EXHAUSTED,
      "exceeds the limit of 2097152 cells (--max_map_cells)");
  ros("PGM width beyond int64", good_yaml, "P5\n99999999999999999999 2\n255\n",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM truncated", good_yaml, "P5\n4 4\n255\n\x01\x02",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM maxval 0", good_yaml,
      std::string("P5\n2 2\n0\n") + std::string(4, '\0'),
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM maxval 70000", good_yaml, "P2\n1 1\n70000\n1\n",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("P2 sample over maxval", good_yaml, "P2\n1 1\n10\n11\n",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  // Files in --map_dir, named by the client.
  const auto from_dir = [&](const std::string& what, const std::string& file,
                            StatusCode code, const std::string& message) {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.set_map_dir_file(file);
    create(what, request, code, message);
  };
  from_dir("map_dir_file '..' escape", "../outside/secret.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file folded '..' escape", "sub/../../outside/secret.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file absolute path", (outside() / "secret.map").string(),
           StatusCode::INVALID_ARGUMENT,
           "must be a path relative to --map_dir");
  from_dir("map_dir_file symlink out", "escape.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file relative symlink out", "escape_relative.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file through a linked directory", "out_dir/secret.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file the directory itself", ".",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  // A link to nothing is a missing file, wherever it would point.
  from_dir("map_dir_file dangling symlink", "dangling.map",
           StatusCode::NOT_FOUND, "map_dir_file 'dangling.map' not found");
  from_dir("map_dir_file empty", "", StatusCode::INVALID_ARGUMENT,
           "map_dir_file is empty");
  from_dir("map_dir_file with NUL", std::string("room\0.map", 9),
           StatusCode::INVALID_ARGUMENT, "NUL");
  from_dir("map_dir_file missing", "missing.map", StatusCode::NOT_FOUND,
           "not found");
  from_dir("map_dir_file a directory", "sub", StatusCode::INVALID_ARGUMENT,
           "not a regular file");
  from_dir("map_dir_file unknown extension", "notes.txt",
           StatusCode::INVALID_ARGUMENT, "unknown extension");
  from_dir("map_dir_file 1 MiB long", std::string(size_t{1} << 20, 'f'),
           StatusCode::INVALID_ARGUMENT,
           "map_dir_file is 1048576 bytes long; the limit is 4096");
  for (const File& f : bad_files_) {
    // Start-up derives the name from the file; here the client names it.
    if (f.name == "bad name.map" || f.name == "..map") continue;
    const StatusCode code =
        f.complaint == "exceeds the limit" ? StatusCode::RESOURCE_EXHAUSTED
        : f.complaint == "not found"       ? StatusCode::NOT_FOUND
                                           : StatusCode::INVALID_ARGUMENT;
    from_dir(absl::StrCat("map_dir_file ", f.name), f.name, code, f.complaint);
  }
  // The request-supplied pose is checked for map_dir Moving AI maps too.
  {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.set_map_dir_file("sub/inner.map");
    request.set_resolution(kNaN);
    create("map_dir_file with NaN resolution", request,
           StatusCode::INVALID_ARGUMENT, "resolution");
  }
  // Oversized: one byte of cells per map cell, beyond --max_message_bytes.
  create("message over --max_message_bytes",
         RawMap("m", 1500, 1500, 1500 * 1500), StatusCode::RESOURCE_EXHAUSTED,
         "larger than max");

  // ---- GetMap / WatchMap answers larger than one message ----
  cases.push_back({"GetMap", "cells of a map larger than one message",
                   [this] { return GetMap("big", /*include_cells=*/true); },
                   StatusCode::RESOURCE_EXHAUSTED, "--max_message_bytes"});
  cases.push_back({"WatchMap", "RESYNC of a map larger than one message",
                   [this] { return WatchMap("big"); },
                   StatusCode::RESOURCE_EXHAUSTED, "--max_message_bytes"});

  // ---- UploadMap: header, bands, an early end ----
  const auto header = [](const std::string& name, int32_t width,
                         int32_t height) {
    v1::UploadMapRequest m;
    m.mutable_header()->set_name(name);
    m.mutable_header()->set_width(width);
    m.mutable_header()->set_height(height);
    return m;
  };
  const auto band = [](int32_t first_row, size_t bytes) {
    v1::UploadMapRequest m;
    m.mutable_band()->set_first_row(first_row);
    m.mutable_band()->set_cells(std::string(bytes, '\0'));
    return m;
  };
  const auto upload = [&](const std::string& what,
                          std::vector<v1::UploadMapRequest> messages,
                          StatusCode code, const std::string& message) {
    cases.push_back({"UploadMap", what,
                     [=, this] { return UploadMap(messages); }, code, message});
  };
  upload("empty stream", {}, StatusCode::INVALID_ARGUMENT,
         "the stream ended before its header; nothing was created");
  upload("band before the header", {band(0, 4)}, StatusCode::INVALID_ARGUMENT,
         "band before the header");
  upload("empty first message", {v1::UploadMapRequest()},
         StatusCode::INVALID_ARGUMENT, "message 1 has neither header nor band");
  upload("second header", {header("m", 4, 4), header("m", 4, 4)},
         StatusCode::INVALID_ARGUMENT, "header: a second header");
  upload("bad name", {header("a b", 4, 4)}, StatusCode::INVALID_ARGUMENT,
         "header.name");
  upload("zero width", {header("m", 0, 4)}, StatusCode::INVALID_ARGUMENT,
         "header.width 0 and header.height 4 must be in 1..65536");
  upload("height over the grid limit", {header("m", 1, 65537)},
         StatusCode::INVALID_ARGUMENT, "header.height 65537");
  upload("INT32_MIN dimensions", {header("m", kIntMin, kIntMin)},
         StatusCode::INVALID_ARGUMENT, "must be in 1..65536");
  upload("over --max_map_cells, refused at the header",
         {header("m", 65536, 65536)}, StatusCode::RESOURCE_EXHAUSTED,
         "exceeds the server's limit of 2097152 cells (--max_map_cells)");
  {
    v1::UploadMapRequest nan = header("m", 4, 4);
    nan.mutable_header()->set_resolution(kNaN);
    upload("NaN resolution", {nan}, StatusCode::INVALID_ARGUMENT,
           "header.resolution");
    v1::UploadMapRequest inf = header("m", 4, 4);
    inf.mutable_header()->mutable_origin()->set_y(-kInf);
    upload("infinite origin", {inf}, StatusCode::INVALID_ARGUMENT,
           "header.origin");
  }
  upload("band out of order", {header("m", 4, 4), band(1, 4)},
         StatusCode::INVALID_ARGUMENT, "band.first_row 1: expected 0");
  upload("band repeated", {header("m", 4, 4), band(0, 8), band(0, 8)},
         StatusCode::INVALID_ARGUMENT, "band.first_row 0: expected 2");
  upload("band not whole rows", {header("m", 4, 4), band(0, 6)},
         StatusCode::INVALID_ARGUMENT,
         "band.cells at row 0: 6 bytes is not a positive whole number of rows "
         "of 4 cells");
  upload("empty band", {header("m", 4, 4), band(0, 0)},
         StatusCode::INVALID_ARGUMENT, "0 bytes is not a positive whole number");
  upload("rows past the height", {header("m", 4, 4), band(0, 8), band(2, 12)},
         StatusCode::INVALID_ARGUMENT,
         "band.cells at row 2: 3 rows pass the header.height of 4");
  upload("header only", {header("m", 4, 4)}, StatusCode::INVALID_ARGUMENT,
         "the stream ended after 0 of header.height 4 rows; nothing was created");
  upload("stream ending early", {header("m", 4, 4), band(0, 12)},
         StatusCode::INVALID_ARGUMENT,
         "the stream ended after 3 of header.height 4 rows; nothing was created");
  upload("name taken without replace", {header("room", 2, 2), band(0, 4)},
         StatusCode::ALREADY_EXISTS, "room");
  upload("band over --max_message_bytes",
         {header("m", 1024, 2048), band(0, 1024 * 2048)},
         StatusCode::RESOURCE_EXHAUSTED, "larger than max");
  // ---- DownloadMap ----
  cases.push_back({"DownloadMap", "unknown map",
                   [this] { return DownloadMap("nope"); },
                   StatusCode::NOT_FOUND, "map 'nope' not found"});
  cases.push_back({"DownloadMap", "bad name",
                   [this] { return DownloadMap("../x"); },
                   StatusCode::INVALID_ARGUMENT, "name"});

  // ---- UpdateMap ----
  const auto update = [&](const std::string& what,
                          std::function<void(v1::UpdateMapRequest&)> fill,
                          StatusCode code, const std::string& message) {
    v1::UpdateMapRequest request;
    request.set_name("room");
    fill(request);
    cases.push_back({"UpdateMap", what,
                     [=, this] { return UpdateMap(request); }, code, message});
  };
  const auto cell = [](int32_t x, int32_t y, uint32_t cost = 254) {
    return [=](v1::UpdateMapRequest& r) {
      v1::CellChange* c = r.add_changes();
      *c->mutable_cell() = CellPos(x, y).cell();
      c->set_cost(cost);
    };
  };
  const auto rect = [](int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                       int count = 1) {
    return [=](v1::UpdateMapRequest& r) {
      for (int i = 0; i < count; ++i) {
        v1::CellChange* c = r.add_changes();
        c->mutable_rect()->set_x_min(x0);
        c->mutable_rect()->set_y_min(y0);
        c->mutable_rect()->set_x_max(x1);
        c->mutable_rect()->set_y_max(y1);
        c->set_cost(static_cast<uint32_t>(i % 2 == 0 ? 254 : 0));
      }
    };
  };
  update(
      "empty batch", [](v1::UpdateMapRequest&) {}, StatusCode::INVALID_ARGUMENT,
      "has no changes");
  update(
      "change with no target", [](v1::UpdateMapRequest& r) { r.add_changes(); },
      StatusCode::INVALID_ARGUMENT, "change 0: neither cell nor rect");
  update("cell (-1, 0)", cell(-1, 0), StatusCode::INVALID_ARGUMENT,
         "change 0: cell (-1, 0) is outside the 16 x 16 map");
  update("cell (16, 3)", cell(16, 3), StatusCode::INVALID_ARGUMENT, "outside");
  update("cell (INT32_MIN, INT32_MAX)", cell(kIntMin, kIntMax),
         StatusCode::INVALID_ARGUMENT, "outside");
  update("cost 256", cell(1, 1, 256), StatusCode::INVALID_ARGUMENT,
         "cost 256 is out of range 0..255");
  update("cost UINT32_MAX", cell(1, 1, 0xffffffffu),
         StatusCode::INVALID_ARGUMENT, "out of range 0..255");
  update("rect min > max", rect(5, 5, 4, 4), StatusCode::INVALID_ARGUMENT,
         "min > max");
  update("rect off the map", rect(0, 0, 16, 15), StatusCode::INVALID_ARGUMENT,
         "reaches outside");
  update("rect INT32_MIN..INT32_MAX", rect(kIntMin, kIntMin, kIntMax, kIntMax),
         StatusCode::INVALID_ARGUMENT, "reaches outside");
  update(
      "bad change after good ones",
      [&](v1::UpdateMapRequest& r) {
        cell(2, 2)(r);
        cell(3, 3)(r);
        cell(99, 3)(r);
      },
      StatusCode::INVALID_ARGUMENT, "change 2:");
  update(
      "stale expected_version",
      [&](v1::UpdateMapRequest& r) {
        cell(2, 2)(r);
        r.set_expected_version(999999);
      },
      StatusCode::ABORTED, "expected 999999");
  // 100 000 whole-map rectangles (about 1 MiB of request): each is legal,
  // but together they would write every cell 100 000 times.
  update("100000 overlapping whole-map rects", rect(0, 0, 15, 15, 100000),
         StatusCode::RESOURCE_EXHAUSTED, "cells in total");
}

}  // namespace pathd::bad_input_test
