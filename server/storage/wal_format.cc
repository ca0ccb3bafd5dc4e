// Framing, CRC32C, record encoding and replay for --data_dir.
#include "server/storage/wal_format.h"

#include <isa-l/crc.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/status_macros.h"

namespace pathd::server::wal {
namespace {

using storage::v1::LogRecord;
using storage::v1::MapImage;
using storage::v1::MapSnapshotRecord;

void PutUint32(uint32_t value, std::string* out) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

uint32_t GetUint32(std::string_view bytes) {
  uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | static_cast<uint8_t>(bytes[i]);
  return value;
}

void FillImage(std::string_view name, uint64_t version, const Grid& grid,
               MapImage* image) {
  image->set_name(std::string(name));
  image->set_version(version);
  image->set_width(grid.width());
  image->set_height(grid.height());
  image->set_resolution(grid.resolution());
  image->set_origin_x(grid.origin().x);
  image->set_origin_y(grid.origin().y);
  image->set_origin_yaw(grid.origin().yaw);
  image->set_cells(reinterpret_cast<const char*>(grid.cells().data()), grid.size());
}

absl::StatusOr<std::string> Serialize(const google::protobuf::Message& message,
                                      std::string_view what) {
  const size_t size = message.ByteSizeLong();
  if (size > kMaxPayloadBytes) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%s needs a %d-byte record; --data_dir stores at most %d bytes per map",
        what, size, kMaxPayloadBytes));
  }
  return message.SerializeAsString();
}

// A frame at the start of `bytes`: its payload, or why there is none.
struct Frame {
  std::string_view payload;
  std::string problem;  // empty when payload is valid
  // The frame claims more bytes than `bytes` has (a torn append).
  bool truncated = false;
};

Frame ReadFrame(std::string_view bytes) {
  Frame frame;
  if (bytes.size() < kFrameHeaderBytes) {
    frame.truncated = true;
    frame.problem = absl::StrFormat("record header cut short (%d of %d bytes)",
                                    bytes.size(), kFrameHeaderBytes);
    return frame;
  }
  const uint32_t length = GetUint32(bytes.substr(0, 4));
  const uint32_t crc = GetUint32(bytes.substr(4, 4));
  if (length == 0) {
    frame.problem = "record length is 0";
    return frame;
  }
  if (length > bytes.size() - kFrameHeaderBytes) {
    frame.truncated = true;
    frame.problem = absl::StrFormat("record of %d bytes cut short (%d present)",
                                    length, bytes.size() - kFrameHeaderBytes);
    return frame;
  }
  const std::string_view payload = bytes.substr(kFrameHeaderBytes, length);
  if (const uint32_t actual = Crc32c(payload); actual != crc) {
    frame.problem = absl::StrFormat(
        "record of %d bytes fails its CRC32C (stored %08x, computed %08x)", length,
        crc, actual);
    return frame;
  }
  frame.payload = payload;
  return frame;
}

// Reads a base-128 varint at bytes[*pos], advancing *pos; false when it
// runs off the end or past 5 bytes (a LogRecord field is under 2 GiB).
bool ReadVarint(std::string_view bytes, size_t* pos, uint64_t* value) {
  *value = 0;
  for (int shift = 0; shift < 35 && *pos < bytes.size(); shift += 7) {
    const auto byte = static_cast<uint8_t>(bytes[(*pos)++]);
    *value |= static_cast<uint64_t>(byte & 0x7f) << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

// A whole file of `magic` followed by exactly one frame: its payload.
absl::StatusOr<std::string_view> ReadSingleFrameFile(std::string_view bytes,
                                                     std::string_view magic,
                                                     std::string_view what) {
  if (bytes.size() < magic.size() || bytes.substr(0, magic.size()) != magic) {
    return absl::DataLossError(
        absl::StrFormat("not a pathd %s (bad magic or empty)", what));
  }
  const std::string_view rest = bytes.substr(magic.size());
  const Frame frame = ReadFrame(rest);
  if (!frame.problem.empty()) return absl::DataLossError(frame.problem);
  if (kFrameHeaderBytes + frame.payload.size() != rest.size()) {
    return absl::DataLossError(
        absl::StrFormat("%d bytes after the %s record",
                        rest.size() - kFrameHeaderBytes - frame.payload.size(), what));
  }
  return frame.payload;
}

absl::Status DataLoss(const std::string& message) {
  return absl::DataLossError(message);
}

}  // namespace

uint32_t Crc32c(std::string_view data) {
  // ISA-L's iSCSI CRC is CRC32C without the final inversion and takes an int
  // length: chunk, and invert around it.
  constexpr size_t kChunk = size_t{1} << 30;
  uint32_t crc = 0xffffffffu;
  // crc32_iscsi does not write through its pointer; its C API is not const.
  auto* p = reinterpret_cast<unsigned char*>(const_cast<char*>(data.data()));
  size_t left = data.size();
  while (left > 0) {
    const size_t n = std::min(left, kChunk);
    crc = crc32_iscsi(p, static_cast<int>(n), crc);
    p += n;
    left -= n;
  }
  return crc ^ 0xffffffffu;
}

void AppendFrame(std::string_view payload, std::string* out) {
  out->reserve(out->size() + kFrameHeaderBytes + payload.size());
  PutUint32(static_cast<uint32_t>(payload.size()), out);
  PutUint32(Crc32c(payload), out);
  out->append(payload);
}

absl::StatusOr<std::string> EncodeCreated(std::string_view name, uint64_t version,
                                          const Grid& grid) {
  LogRecord record;
  FillImage(name, version, grid, record.mutable_created());
  PATHD_ASSIGN_OR_RETURN(const std::string payload,
                         Serialize(record, absl::StrFormat("map '%s'", name)));
  std::string framed;
  AppendFrame(payload, &framed);
  return framed;
}

std::string EncodeUpdated(std::string_view name, uint64_t version,
                          absl::Span<const MapChange> changes) {
  LogRecord record;
  storage::v1::MapUpdated* updated = record.mutable_updated();
  updated->set_name(std::string(name));
  updated->set_version(version);
  updated->mutable_fills()->Reserve(static_cast<int>(changes.size()));
  for (const MapChange& change : changes) {
    storage::v1::CellFill* fill = updated->add_fills();
    fill->set_x_min(change.x_min);
    fill->set_y_min(change.y_min);
    fill->set_x_max(change.x_max);
    fill->set_y_max(change.y_max);
    fill->set_cost(change.cost);
  }
  std::string framed;
  // An update's size is bounded by the gRPC message it came in.
  AppendFrame(record.SerializeAsString(), &framed);
  return framed;
}

std::string EncodeDeleted(std::string_view name, uint64_t last_version) {
  LogRecord record;
  record.mutable_deleted()->set_name(std::string(name));
  record.mutable_deleted()->set_last_version(last_version);
  std::string framed;
  AppendFrame(record.SerializeAsString(), &framed);
  return framed;
}

absl::StatusOr<std::string> EncodeSnapshot(uint64_t sequence, std::string_view name,
                                           uint64_t version, const Grid& grid) {
  MapSnapshotRecord snapshot;
  snapshot.set_sequence(sequence);
  FillImage(name, version, grid, snapshot.mutable_map());
  PATHD_ASSIGN_OR_RETURN(const std::string payload,
                         Serialize(snapshot, absl::StrFormat("map '%s'", name)));
  std::string file(kSnapshotMagic);
  AppendFrame(payload, &file);
  return file;
}

absl::StatusOr<LogScan> ParseLogSegment(std::string_view bytes) {
  LogScan scan;
  if (bytes.size() < kLogMagic.size()) {
    // A crash while the segment was being created; nothing was appended yet.
    if (kLogMagic.substr(0, bytes.size()) == bytes) {
      if (!bytes.empty()) {
        scan.torn_tail = absl::StrFormat("segment header cut short (%d of %d bytes)",
                                         bytes.size(), kLogMagic.size());
      }
      return scan;
    }
    return DataLoss("offset 0: not a pathd log segment (bad magic)");
  }
  if (bytes.substr(0, kLogMagic.size()) != kLogMagic) {
    return DataLoss("offset 0: not a pathd log segment (bad magic)");
  }
  size_t offset = kLogMagic.size();
  scan.valid_bytes = offset;
  while (offset < bytes.size()) {
    const Frame frame = ReadFrame(bytes.substr(offset));
    if (frame.problem.empty()) {
      LogEntry entry;
      entry.offset = offset;
      if (!entry.record.ParseFromArray(frame.payload.data(),
                                       static_cast<int>(frame.payload.size())) ||
          entry.record.change_case() == LogRecord::CHANGE_NOT_SET) {
        // The CRC matched, so these are the bytes that were written: not a
        // torn append but a bad writer. Never skip it.
        return DataLoss(absl::StrFormat(
            "offset %d: record passes its CRC32C but is not a log record", offset));
      }
      scan.entries.push_back(std::move(entry));
      offset += kFrameHeaderBytes + frame.payload.size();
      scan.valid_bytes = offset;
      continue;
    }
    // A torn append leaves a cut-short frame, or (when the file grew before
    // its data reached the disk) one followed only by zeros: nothing valid
    // can follow a torn record. A damaged length field also makes a frame
    // look cut short, so the rest is searched for a valid record; finding
    // one means data the log would silently lose.
    if (const size_t next = FindValidRecord(bytes, offset + 1);
        next != std::string_view::npos) {
      return DataLoss(absl::StrFormat(
          "offset %d: %s, and a valid record follows at offset %d (%d bytes of data "
          "after the damage)",
          offset, frame.problem, next, bytes.size() - next));
    }
    scan.torn_tail = frame.problem;
    scan.tail_cut_short = frame.truncated;
    return scan;
  }
  return scan;
}

size_t FindValidRecord(std::string_view bytes, size_t from) {
  for (size_t k = from; k + kFrameHeaderBytes < bytes.size(); ++k) {
    const uint32_t length = GetUint32(bytes.substr(k, 4));
    if (length == 0 || length > bytes.size() - k - kFrameHeaderBytes) continue;
    // A LogRecord is exactly one length-delimited field (created = 1,
    // updated = 2, deleted = 3) filling the payload: tag, varint, message.
    const std::string_view payload = bytes.substr(k + kFrameHeaderBytes, length);
    const auto tag = static_cast<uint8_t>(payload[0]);
    if (tag != 0x0a && tag != 0x12 && tag != 0x1a) continue;
    size_t pos = 1;
    uint64_t field_bytes = 0;
    if (!ReadVarint(payload, &pos, &field_bytes) || pos + field_bytes != length) continue;
    if (Crc32c(payload) != GetUint32(bytes.substr(k + 4, 4))) continue;
    LogRecord record;
    if (record.ParseFromArray(payload.data(), static_cast<int>(payload.size())) &&
        record.change_case() != LogRecord::CHANGE_NOT_SET) {
      return k;
    }
  }
  return std::string_view::npos;
}

std::string EncodeCheckpoint(const storage::v1::CheckpointRecord& checkpoint) {
  std::string file(kCheckpointMagic);
  // A name and a number per map: far below kMaxPayloadBytes.
  AppendFrame(checkpoint.SerializeAsString(), &file);
  return file;
}

absl::StatusOr<storage::v1::CheckpointRecord> ParseCheckpoint(std::string_view bytes) {
  PATHD_ASSIGN_OR_RETURN(const std::string_view payload,
                         ReadSingleFrameFile(bytes, kCheckpointMagic, "checkpoint"));
  storage::v1::CheckpointRecord checkpoint;
  if (!checkpoint.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) {
    return DataLoss("record passes its CRC32C but is not a checkpoint");
  }
  if (checkpoint.first_sequence() == 0) return DataLoss("checkpoint at sequence 0");
  return checkpoint;
}

absl::StatusOr<MapSnapshotRecord> ParseSnapshot(std::string_view bytes) {
  PATHD_ASSIGN_OR_RETURN(const std::string_view payload,
                         ReadSingleFrameFile(bytes, kSnapshotMagic, "snapshot"));
  MapSnapshotRecord snapshot;
  if (!snapshot.ParseFromArray(payload.data(), static_cast<int>(payload.size())) ||
      !snapshot.has_map()) {
    return DataLoss("record passes its CRC32C but is not a map snapshot");
  }
  if (snapshot.sequence() == 0 || snapshot.map().version() == 0) {
    return DataLoss("snapshot has sequence or version 0");
  }
  return snapshot;
}

absl::StatusOr<Grid> GridFromImage(const MapImage& image) {
  if (absl::Status name = MapStore::ValidateName(image.name()); !name.ok()) {
    return DataLoss(std::string(name.message()));
  }
  if (image.width() < 1 || image.height() < 1 || image.width() > kMaxGridDimension ||
      image.height() > kMaxGridDimension) {
    return DataLoss(absl::StrFormat("map '%s' has impossible size %d x %d",
                                    image.name(), image.width(), image.height()));
  }
  const size_t cells =
      static_cast<size_t>(image.width()) * static_cast<size_t>(image.height());
  if (image.cells().size() != cells) {
    return DataLoss(absl::StrFormat("map '%s' (%d x %d) holds %d cells, not %d",
                                    image.name(), image.width(), image.height(),
                                    image.cells().size(), cells));
  }
  if (!std::isfinite(image.resolution()) || image.resolution() <= 0.0 ||
      !std::isfinite(image.origin_x()) || !std::isfinite(image.origin_y()) ||
      !std::isfinite(image.origin_yaw())) {
    return DataLoss(absl::StrFormat("map '%s' has a bad resolution or origin",
                                    image.name()));
  }
  std::vector<uint8_t> bytes(image.cells().begin(), image.cells().end());
  PATHD_ASSIGN_OR_RETURN(Grid grid,
                         Grid::FromCells(image.width(), image.height(), std::move(bytes)));
  grid.set_resolution(image.resolution());
  grid.set_origin(GridOrigin{image.origin_x(), image.origin_y(), image.origin_yaw()});
  return grid;
}

absl::Status Replayer::AddSnapshot(const MapSnapshotRecord& snapshot) {
  const MapImage& image = snapshot.map();
  PATHD_ASSIGN_OR_RETURN(Grid grid, GridFromImage(image));
  NameState& state = names_[image.name()];
  if (state.snapshot_sequence != 0) {
    return DataLoss(absl::StrFormat("two snapshots of map '%s'", image.name()));
  }
  state.has_map = true;
  state.map = Map{std::move(grid), image.version()};
  state.snapshot_sequence = snapshot.sequence();
  state.last_sequence = snapshot.sequence();
  return absl::OkStatus();
}

absl::Status Replayer::Apply(uint64_t sequence, const LogRecord& record) {
  switch (record.change_case()) {
    case LogRecord::kCreated: {
      const MapImage& image = record.created();
      auto it = names_.find(image.name());
      if (it != names_.end() && sequence <= it->second.snapshot_sequence) {
        return absl::OkStatus();
      }
      PATHD_ASSIGN_OR_RETURN(Grid grid, GridFromImage(image));
      NameState& state = it != names_.end() ? it->second : names_[image.name()];
      // MapStore::Create: 1 for a new name, the old version + 1 on replace.
      const uint64_t expected = state.has_map ? state.map.version + 1 : 1;
      if (image.version() != expected) {
        return DataLoss(absl::StrFormat(
            "creation of map '%s' at version %d, but the map is at %s", image.name(),
            image.version(),
            state.has_map ? absl::StrFormat("version %d", state.map.version)
                          : std::string("no version (absent)")));
      }
      state.has_map = true;
      state.map = Map{std::move(grid), image.version()};
      state.last_sequence = sequence;
      return absl::OkStatus();
    }
    case LogRecord::kUpdated: {
      const storage::v1::MapUpdated& updated = record.updated();
      auto it = names_.find(updated.name());
      if (it != names_.end() && sequence <= it->second.snapshot_sequence) {
        return absl::OkStatus();
      }
      if (it == names_.end() || !it->second.has_map) {
        return DataLoss(absl::StrFormat("update of map '%s' to version %d, which does "
                                        "not exist at that point of the log",
                                        updated.name(), updated.version()));
      }
      NameState& state = it->second;
      if (updated.version() != state.map.version + 1) {
        return DataLoss(absl::StrFormat(
            "update of map '%s' to version %d, but the map is at version %d",
            updated.name(), updated.version(), state.map.version));
      }
      Grid& grid = state.map.grid;
      for (int i = 0; i < updated.fills_size(); ++i) {
        const storage::v1::CellFill& fill = updated.fills(i);
        if (fill.cost() > 255 || fill.x_min() > fill.x_max() ||
            fill.y_min() > fill.y_max() || !grid.InBounds(fill.x_min(), fill.y_min()) ||
            !grid.InBounds(fill.x_max(), fill.y_max())) {
          return DataLoss(absl::StrFormat(
              "update of map '%s' to version %d: change %d is not a valid change of "
              "the %d x %d map",
              updated.name(), updated.version(), i, grid.width(), grid.height()));
        }
      }
      for (const storage::v1::CellFill& fill : updated.fills()) {
        uint8_t* cells = grid.mutable_cells().data();
        const auto width = static_cast<size_t>(fill.x_max() - fill.x_min()) + 1;
        for (int32_t y = fill.y_min(); y <= fill.y_max(); ++y) {
          std::fill_n(cells + grid.Index(fill.x_min(), y), width,
                      static_cast<uint8_t>(fill.cost()));
        }
      }
      state.map.version = updated.version();
      state.last_sequence = sequence;
      return absl::OkStatus();
    }
    case LogRecord::kDeleted: {
      const storage::v1::MapDeleted& deleted = record.deleted();
      auto it = names_.find(deleted.name());
      if (it != names_.end() && sequence <= it->second.snapshot_sequence) {
        return absl::OkStatus();
      }
      if (it == names_.end() || !it->second.has_map ||
          it->second.map.version != deleted.last_version()) {
        return DataLoss(absl::StrFormat(
            "deletion of map '%s' at version %d, which does not exist at that point "
            "of the log",
            deleted.name(), deleted.last_version()));
      }
      it->second.has_map = false;
      it->second.map = Map{};
      it->second.last_sequence = sequence;
      return absl::OkStatus();
    }
    case LogRecord::CHANGE_NOT_SET:
      break;
  }
  return DataLoss("log record holds no change");
}

}  // namespace pathd::server::wal
