/// \file EngineAbort.cpp
/// Engine::Impl::abort: the message of a run that stops on a non-finite state or an overlap beyond
/// run.max_overlap, naming the particles, the time step and, for an attractive Coulomb pair, the
/// contact model's own limit (ContactModels.h, attractionLimit) and the charge scale that keeps
/// K Q^2 below it. Cold code: it runs once, when the force pass has flagged the step.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "md/engine/EngineImpl.h"

namespace granagg::md {

using engine_detail::toHostById;

void Engine::Impl::abort(int worst) {
  DVec<double> mx_slots;
  maxOverlapPerParticle(p, nl, box, contact, mx_slots);
  const auto mx = toHostById(mx_slots, p.id);
  // which particles: the force pass's test again, per particle (cold path)
  const auto pos = toHostById(p.pos, p.id);
  DVec<double> dfx, dfy, dfz;
  unpackVec3(p.force, dfx, dfy, dfz);
  const auto fx = toHostById(dfx, p.id), fy = toHostById(dfy, p.id), fz = toHostById(dfz, p.id);
  std::vector<int> bad(pos.size(), 0);
  for (std::size_t i = 0; i < bad.size(); ++i) {
    const bool finite = std::isfinite(pos[i].x + pos[i].y + pos[i].z + fx[i] + fy[i] + fz[i]);
    bad[i] = !finite ? 1 : (mx[i] > cfg.run.max_overlap ? 2 : 0);
  }
  std::ostringstream msg;
  msg << "step " << step << " (t = " << time << "): ";
  msg << (worst == 1 ? "non-finite force or position (NaN/inf)"
                     : "overlap beyond run.max_overlap = ");
  if (worst != 1) msg << cfg.run.max_overlap;
  msg << " for particle(s)";
  int shown = 0;
  for (std::size_t i = 0; i < bad.size() && shown < 8; ++i)
    if (bad[i]) {
      msg << (shown ? ", " : " ") << i;
      if (bad[i] == 2) msg << " (overlap " << mx[i] << ")";
      ++shown;
    }
  msg << "; the time step dt = " << dt << " may be too large for these impacts";
  if (coulomb && worst == 2) {
    // An attractive pair has an equilibrium overlap only up to the contact model's limit.
    std::string how;
    const double hold = std::visit(
        [&how](const auto& m) {
          return std::decay_t<decltype(m)>::Model::attractionLimit(m.params, how);
        },
        contact);
    const char* model =
        std::visit([](const auto& m) { return std::decay_t<decltype(m)>::Model::name; }, contact);
    double worst_qq = 0.0;
    for (std::size_t i = 0; i < bad.size(); ++i)
      if (bad[i] == 2) worst_qq = std::max(worst_qq, pos[i].w * pos[i].w);
    msg << ", or an attractive Coulomb pair beyond what the " << model
        << " contact can hold (K |q_i q_j| > " << how << " = " << hold
        << " has no equilibrium overlap; here K q^2 = " << cfg.coulomb.K * worst_qq
        << " for the largest flagged charge): lower charging.Q (here " << cfg.charging.Q
        << "; recommended: 0.05 at K = 5, docs/validation.md";
    char q[32];  // two digits: a value to type
    std::snprintf(q, sizeof q, "%.2g", recommendedChargeScale(cfg.coulomb.K));
    if (cfg.coulomb.K != 5.0)  // the gas depends on K Q^2 only
      msg << ", so " << q << " at K = " << cfg.coulomb.K << ", the same K Q^2";
    msg << ": --set charging.Q=" << q << ") or coulomb.K";
  }
  throw RunAborted(msg.str());
}

}  // namespace granagg::md
