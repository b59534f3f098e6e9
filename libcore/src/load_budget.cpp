// SPDX-License-Identifier: MIT
#include "isokit/core/load_budget.h"

#include <limits>

namespace isokit {

namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

std::string mib(std::uint64_t bytes) {
  return format_number(static_cast<double>(bytes) / (1024.0 * 1024.0)) + " MiB";
}

}  // namespace

std::uint64_t load_budget_bytes(std::uint64_t input_bytes) {
  const std::uint64_t per = LoadBudgetRule::kBytesPerInputByte;
  if (input_bytes > (kMax - LoadBudgetRule::kFixedBytes) / per) return kMax;
  return per * input_bytes + LoadBudgetRule::kFixedBytes;
}

LoadBudget::LoadBudget(std::string file, std::uint64_t input_bytes)
    : file_(std::move(file)), input_(input_bytes) {}

void LoadBudget::add_input(std::uint64_t bytes) {
  input_ = bytes > kMax - input_ ? kMax : input_ + bytes;
}

void LoadBudget::charge(std::uint64_t bytes, const std::string& item) {
  const std::uint64_t total = bytes > kMax - used_ ? kMax : used_ + bytes;
  if (total > limit())
    throw InputError((item.rfind(file_, 0) == 0 ? item : file_ + ": " + item) + ": declares " +
                     std::to_string(bytes) + " bytes, past the load budget of " + mib(limit()) + " (" +
                     std::to_string(LoadBudgetRule::kBytesPerInputByte) + " x the " + std::to_string(input_) +
                     "-byte input + " + mib(LoadBudgetRule::kFixedBytes) + "; " + mib(used_) +
                     " already taken); the file is corrupt or hostile: export it again");
  used_ = total;
}

void LoadBudget::charge(std::uint64_t count, std::uint64_t element_bytes, const std::string& item) {
  const std::uint64_t bytes =
      element_bytes != 0 && count > kMax / element_bytes ? kMax : count * element_bytes;
  charge(bytes, item);
}

}  // namespace isokit
