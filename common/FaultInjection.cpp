#include "common/FaultInjection.h"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace granagg::common {
namespace {

struct Fault {
  enum class Action { none, kill, enospc, count } action = Action::none;
  std::string site;
  long long k = 0;
};

Fault parseFault() {
  Fault f;
  const char* env = std::getenv("GRANAGG_FAULT");
  if (!env || !*env) return f;
  const std::string s(env);
  const auto a = s.find(':'), b = s.rfind(':');
  char* end = nullptr;
  const long long k = (a != b) ? std::strtoll(s.c_str() + b + 1, &end, 10) : 0;
  const std::string action = s.substr(0, a == std::string::npos ? 0 : a);
  if (a == b || k < 1 || !end || *end != '\0' ||
      (action != "kill" && action != "enospc" && action != "count")) {
    std::fprintf(stderr,
                 "granagg: ignoring GRANAGG_FAULT='%s' (expected kill|enospc|count:<site>:<K>, "
                 "K >= 1)\n",
                 env);
    return f;
  }
  f.action = action == "kill"     ? Fault::Action::kill
             : action == "enospc" ? Fault::Action::enospc
                                  : Fault::Action::count;
  f.site = s.substr(a + 1, b - a - 1);
  f.k = k;
  return f;
}

}  // namespace

static std::atomic<long long> passages{0};
static std::string counted_site;

static void reportCount() {
  std::fprintf(stderr, "granagg: fault point %s passed %lld times\n", counted_site.c_str(),
               passages.load());
}

bool faultPoint(const char* site) {
  static const Fault fault = [] {
    Fault f = parseFault();
    if (f.action == Fault::Action::count) {
      counted_site = f.site;
      std::atexit(reportCount);
    }
    return f;
  }();
  if (fault.action == Fault::Action::none || fault.site != site) return false;
  const long long n = ++passages;
  if (fault.action == Fault::Action::count || n < fault.k) return false;
  if (fault.action == Fault::Action::kill) {
    std::raise(SIGKILL);
  }
  return true;
}

}  // namespace granagg::common
