// ThreadSanitizer-only shim that makes Debian's uninstrumented absl::Mutex
// and absl::CondVar visible to TSan. Linked into test executables of the
// PATHD_TSAN build only (never into pathd).
//
// Debian builds libabsl_synchronization without -fsanitize=thread, so the
// __tsan_mutex_* annotations Abseil's mutex.cc carries under TSan are compiled
// out: TSan sees neither our absl::Mutex sections nor the ones inside gRPC
// (grpc_core::Mutex and gpr_mu are absl::Mutex in gRPC 1.51) and reports every
// access they order as a race. This file defines the public lock entry points
// in the executable, which exports them (ENABLE_EXPORTS), so both our code and
// the shared libraries (libgrpc, libgpr, Abseil's own Notification...) bind to
// them; each one brackets the real function, found with dlsym(RTLD_NEXT), with
// the same annotations upstream mutex.cc makes. TSan then treats absl::Mutex
// as a real reader-writer mutex: happens-before, lock-order inversion and
// bad-unlock reports included.
//
// The entry points are exactly the out-of-line ones the library exports that
// do not call another exported one (checked with objdump: the *WithTimeout
// variants tail-call the *WithDeadline ones through the PLT, so shimming the
// latter covers both). Condition predicates run inside the real calls, between
// pre and post annotations, where TSan ignores memory accesses, as upstream.
#if !defined(__SANITIZE_THREAD__)
#if defined(__has_feature)
#if !__has_feature(thread_sanitizer)
#error "absl_mutex_tsan.cc belongs to the -fsanitize=thread build only"
#endif
#else
#error "absl_mutex_tsan.cc belongs to the -fsanitize=thread build only"
#endif
#endif

#include <dlfcn.h>
#include <sanitizer/tsan_interface.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"

#define PATHD_STRINGIFY_INNER(x) #x
#define PATHD_STRINGIFY(x) PATHD_STRINGIFY_INNER(x)

namespace {

// The real library function whose Itanium-mangled name is
// _ZN4absl<inline namespace><suffix>, e.g. suffix "5Mutex4LockEv". Aborts
// when it is missing: a silently unannotated lock would bring the false
// reports back.
void* Real(const char* suffix) {
#ifdef ABSL_OPTION_INLINE_NAMESPACE_NAME
  const std::string ns = PATHD_STRINGIFY(ABSL_OPTION_INLINE_NAMESPACE_NAME);
  const std::string name =
      "_ZN4absl" + std::to_string(ns.size()) + ns + std::string(suffix);
#else
  const std::string name = "_ZN4absl" + std::string(suffix);
#endif
  void* fn = dlsym(RTLD_NEXT, name.c_str());
  if (fn == nullptr) {
    std::fprintf(stderr, "absl_mutex_tsan: %s not found in the shared Abseil\n",
                 name.c_str());
    std::abort();
  }
  return fn;
}

// Resolved once per entry point (function-local statics are thread-safe).
template <typename Fn>
Fn RealFn(const char* suffix) {
  return reinterpret_cast<Fn>(Real(suffix));
}

// Mutexes this thread holds in shared mode, so Await and CondVar::Wait (which
// release and re-take the mutex in the mode it is held) annotate the right
// mode. Upstream reads the mutex word for this; the word is not ours to read.
thread_local std::vector<const absl::Mutex*> reader_held;

void NoteReaderLocked(const absl::Mutex* mu) { reader_held.push_back(mu); }

void NoteReaderUnlocked(const absl::Mutex* mu) {
  auto it = std::find(reader_held.rbegin(), reader_held.rend(), mu);
  if (it != reader_held.rend()) reader_held.erase(std::next(it).base());
}

unsigned ModeFlags(const absl::Mutex* mu) {
  return std::find(reader_held.begin(), reader_held.end(), mu) !=
                 reader_held.end()
             ? __tsan_mutex_read_lock
             : 0;
}

// Brackets a blocking wait that releases `mu` and takes it back in the same
// mode: TSan sees an unlock before and a lock after.
template <typename Wait>
bool AnnotatedWait(absl::Mutex* mu, Wait wait) {
  const unsigned flags = ModeFlags(mu);
  __tsan_mutex_pre_unlock(mu, flags);
  __tsan_mutex_post_unlock(mu, flags);
  const bool result = wait();
  __tsan_mutex_pre_lock(mu, flags);
  __tsan_mutex_post_lock(mu, flags, 0);
  return result;
}

}  // namespace

namespace absl {
ABSL_NAMESPACE_BEGIN

Mutex::~Mutex() {
  static const auto real = RealFn<void (*)(Mutex*)>("5MutexD2Ev");
  __tsan_mutex_destroy(this, __tsan_mutex_not_static);
  real(this);
}

void Mutex::Lock() {
  static const auto real = RealFn<void (*)(Mutex*)>("5Mutex4LockEv");
  __tsan_mutex_pre_lock(this, 0);
  real(this);
  __tsan_mutex_post_lock(this, 0, 0);
}

void Mutex::ReaderLock() {
  static const auto real = RealFn<void (*)(Mutex*)>("5Mutex10ReaderLockEv");
  __tsan_mutex_pre_lock(this, __tsan_mutex_read_lock);
  real(this);
  __tsan_mutex_post_lock(this, __tsan_mutex_read_lock, 0);
  NoteReaderLocked(this);
}

bool Mutex::TryLock() {
  static const auto real = RealFn<bool (*)(Mutex*)>("5Mutex7TryLockEv");
  __tsan_mutex_pre_lock(this, __tsan_mutex_try_lock);
  const bool locked = real(this);
  __tsan_mutex_post_lock(
      this, __tsan_mutex_try_lock | (locked ? 0 : __tsan_mutex_try_lock_failed),
      0);
  return locked;
}

bool Mutex::ReaderTryLock() {
  static const auto real = RealFn<bool (*)(Mutex*)>("5Mutex13ReaderTryLockEv");
  const unsigned flags = __tsan_mutex_read_lock | __tsan_mutex_try_lock;
  __tsan_mutex_pre_lock(this, flags);
  const bool locked = real(this);
  __tsan_mutex_post_lock(
      this, flags | (locked ? 0 : __tsan_mutex_try_lock_failed), 0);
  if (locked) NoteReaderLocked(this);
  return locked;
}

void Mutex::Unlock() {
  static const auto real = RealFn<void (*)(Mutex*)>("5Mutex6UnlockEv");
  __tsan_mutex_pre_unlock(this, 0);
  real(this);
  __tsan_mutex_post_unlock(this, 0);
}

void Mutex::ReaderUnlock() {
  static const auto real = RealFn<void (*)(Mutex*)>("5Mutex12ReaderUnlockEv");
  NoteReaderUnlocked(this);
  __tsan_mutex_pre_unlock(this, __tsan_mutex_read_lock);
  real(this);
  __tsan_mutex_post_unlock(this, __tsan_mutex_read_lock);
}

void Mutex::LockWhen(const Condition& cond) {
  static const auto real = RealFn<void (*)(Mutex*, const Condition&)>(
      "5Mutex8LockWhenERKNS0_9ConditionE");
  __tsan_mutex_pre_lock(this, 0);
  real(this, cond);
  __tsan_mutex_post_lock(this, 0, 0);
}

void Mutex::ReaderLockWhen(const Condition& cond) {
  static const auto real = RealFn<void (*)(Mutex*, const Condition&)>(
      "5Mutex14ReaderLockWhenERKNS0_9ConditionE");
  __tsan_mutex_pre_lock(this, __tsan_mutex_read_lock);
  real(this, cond);
  __tsan_mutex_post_lock(this, __tsan_mutex_read_lock, 0);
  NoteReaderLocked(this);
}

bool Mutex::LockWhenWithDeadline(const Condition& cond, absl::Time deadline) {
  static const auto real =
      RealFn<bool (*)(Mutex*, const Condition&, absl::Time)>(
          "5Mutex20LockWhenWithDeadlineERKNS0_9ConditionENS0_4TimeE");
  __tsan_mutex_pre_lock(this, 0);
  const bool result = real(this, cond, deadline);
  __tsan_mutex_post_lock(this, 0, 0);
  return result;
}

bool Mutex::ReaderLockWhenWithDeadline(const Condition& cond,
                                       absl::Time deadline) {
  static const auto real =
      RealFn<bool (*)(Mutex*, const Condition&, absl::Time)>(
          "5Mutex26ReaderLockWhenWithDeadlineERKNS0_9ConditionENS0_4TimeE");
  __tsan_mutex_pre_lock(this, __tsan_mutex_read_lock);
  const bool result = real(this, cond, deadline);
  __tsan_mutex_post_lock(this, __tsan_mutex_read_lock, 0);
  NoteReaderLocked(this);
  return result;
}

void Mutex::Await(const Condition& cond) {
  static const auto real = RealFn<void (*)(Mutex*, const Condition&)>(
      "5Mutex5AwaitERKNS0_9ConditionE");
  AnnotatedWait(this, [&] {
    real(this, cond);
    return true;
  });
}

bool Mutex::AwaitWithDeadline(const Condition& cond, absl::Time deadline) {
  static const auto real =
      RealFn<bool (*)(Mutex*, const Condition&, absl::Time)>(
          "5Mutex17AwaitWithDeadlineERKNS0_9ConditionENS0_4TimeE");
  return AnnotatedWait(this, [&] { return real(this, cond, deadline); });
}

void CondVar::Wait(Mutex* mu) {
  static const auto real =
      RealFn<void (*)(CondVar*, Mutex*)>("7CondVar4WaitEPNS0_5MutexE");
  AnnotatedWait(mu, [&] {
    real(this, mu);
    return true;
  });
}

bool CondVar::WaitWithDeadline(Mutex* mu, absl::Time deadline) {
  static const auto real = RealFn<bool (*)(CondVar*, Mutex*, absl::Time)>(
      "7CondVar16WaitWithDeadlineEPNS0_5MutexENS0_4TimeE");
  return AnnotatedWait(mu, [&] { return real(this, mu, deadline); });
}

ABSL_NAMESPACE_END
}  // namespace absl
