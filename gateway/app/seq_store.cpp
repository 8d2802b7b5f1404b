#include "app/seq_store.hpp"

#include <algorithm>
#include <string>

#include "state_file.hpp"

namespace gateway {

SeqStore::SeqStore(std::filesystem::path dir, std::uint32_t network, std::uint64_t block, WallClock wall)
    : file_(dir.empty() ? std::filesystem::path() : dir / ("seq-net" + std::to_string(network))),
      block_(std::max<std::uint64_t>(block, 1)),
      wall_(std::move(wall)) {}

SeqStore::Opened SeqStore::open() {
  Opened out;
  if (file_.empty()) {
    bound_ = UINT64_MAX;  // nothing to reserve
    return out;
  }
  std::uint64_t stored = 0;
  const NumberFile read = read_number_file(file_, stored);
  if (read == NumberFile::Ok && stored != 0) {  // 0 is no number of a run: seq starts at 1
    out.first = stored;
  } else {
    const bool missing = read == NumberFile::Missing;
    const auto us = std::chrono::duration_cast<std::chrono::microseconds>(wall_().time_since_epoch()).count();
    out.first = std::max<std::uint64_t>(1, us > 0 ? static_cast<std::uint64_t>(us) : 0);
    out.corrupt = !missing;
    out.note = std::string(missing ? "no stored seq in " : "stored seq unreadable in ") + file_.string() +
               ": starting at the wall-clock time in microseconds, " + std::to_string(out.first) +
               ", above any number an earlier run used";
  }
  bound_ = out.first + block_;
  out.error = store(bound_);
  return out;
}

std::error_code SeqStore::use(std::uint64_t seq) {
  if (file_.empty() || seq < bound_) return {};
  bound_ = seq + block_;
  return store(bound_);
}

std::error_code SeqStore::close(std::uint64_t next) {
  if (file_.empty()) return {};
  bound_ = next;
  return store(next);
}

std::error_code SeqStore::store(std::uint64_t value) { return write_durably(file_, std::to_string(value) + "\n"); }

}  // namespace gateway
