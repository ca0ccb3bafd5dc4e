// Small helpers for absl::Status propagation. Abseil 20220623 ships no
// RETURN_IF_ERROR / ASSIGN_OR_RETURN, so pathd keeps its own.
#ifndef PATHD_CORE_STATUS_MACROS_H_
#define PATHD_CORE_STATUS_MACROS_H_

#include "absl/status/status.h"
#include "absl/status/statusor.h"

#define PATHD_CONCAT_INNER_(a, b) a##b
#define PATHD_CONCAT_(a, b) PATHD_CONCAT_INNER_(a, b)

// Returns from the enclosing function when `expr` (an absl::Status) is not OK.
#define PATHD_RETURN_IF_ERROR(expr)                 \
  do {                                              \
    if (::absl::Status pathd_status_ = (expr);      \
        !pathd_status_.ok()) {                      \
      return pathd_status_;                         \
    }                                               \
  } while (false)

// `lhs = value of expr` when `expr` (an absl::StatusOr<T>) holds a value,
// otherwise returns its status from the enclosing function.
#define PATHD_ASSIGN_OR_RETURN(lhs, expr) \
  PATHD_ASSIGN_OR_RETURN_IMPL_(PATHD_CONCAT_(pathd_statusor_, __LINE__), lhs, expr)

#define PATHD_ASSIGN_OR_RETURN_IMPL_(var, lhs, expr) \
  auto var = (expr);                                 \
  if (!var.ok()) return std::move(var).status();     \
  lhs = std::move(var).value()

#endif  // PATHD_CORE_STATUS_MACROS_H_
