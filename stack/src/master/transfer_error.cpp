#include "canopen/master/transfer_error.hpp"

#include <string>

namespace canopen::master {

namespace {

class TransferErrorCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "canopen.transfer"; }
  std::string message(int v) const override {
    switch (static_cast<TransferError>(v)) {
      case TransferError::BadNode: return "node-ID must be 1..127";
      case TransferError::Busy: return "a DCF read, DCF apply or program download is already running for the node";
      case TransferError::BadProgramNumber: return "program number must be 1..254";
      case TransferError::EmptyImage: return "the program image is empty";
      case TransferError::NothingToTransfer: return "nothing to transfer: no configurable object with a value";
      case TransferError::WrongIdentification: return "the program software identification (1F56h) is not the expected one";
    }
    return "unknown transfer error";
  }
};

}  // namespace

const std::error_category& transfer_error_category() {
  static const TransferErrorCategory cat;
  return cat;
}

std::error_code make_error_code(TransferError e) { return {static_cast<int>(e), transfer_error_category()}; }

}  // namespace canopen::master
