#include "sparkplug/bdseq_store.hpp"

#include "state_file.hpp"

namespace gateway::sparkplug {

BdSeqStore::BdSeqStore(std::filesystem::path dir)
    : file_(dir.empty() ? std::filesystem::path() : dir / "sparkplug-bdseq") {}

BdSeqStore::Next BdSeqStore::next() {
  Next out;
  if (!read_) {
    read_ = true;
    std::uint64_t stored = 0;
    NumberFile r = file_.empty() ? NumberFile::Missing : read_number_file(file_, stored);
    if (r == NumberFile::Ok && stored > 255) r = NumberFile::Unreadable;
    if (r == NumberFile::Ok) current_ = static_cast<std::uint8_t>(stored);
    if (r == NumberFile::Unreadable)
      out.note = "stored Sparkplug bdSeq unreadable in " + file_.string() + ": starting at 0";
  }
  // uint8_t arithmetic: 255 + 1 wraps to 0 (spec ch4 bdseq-increment).
  out.bd_seq = current_ ? static_cast<std::uint8_t>(*current_ + 1) : std::uint8_t{0};
  current_ = out.bd_seq;
  if (!file_.empty()) out.error = write_durably(file_, std::to_string(out.bd_seq) + "\n");
  return out;
}

}  // namespace gateway::sparkplug
