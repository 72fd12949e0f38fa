#pragma once
/// \file ContactModels.h
/// The list of contact models (HOOMD-blue's evaluator list, in one place). A model is a header in
/// md/potentials/ with
///   - `Params` and the device-side physics: `normalForce(xi, xi_dot, params)`,
///     `elasticEnergy(xi, params)` (HD, called per pair by md/compute/ContactForce);
///   - `name`, the value of `contact.model` that selects it;
///   - `fromConfig(ContactConfig, m_eff)`, `autoContactTime(params, v, m_eff, why)` and
///     `attractionLimit(params, how)`, the strongest Coulomb attraction a static contact
///     balances, for the engine's message when oppositely charged pairs collapse (host).
/// The engine holds a ContactModel and never names a model; md/compute/ContactForce dispatches
/// on it with std::visit, which instantiates the force pass for every model in the list.
/// Adding a model: its header, one entry in ContactModel below, a test in
/// tests/md/test_contact_forces.cpp (and its keys in md/config).
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "md/config/MdConfig.h"
#include "md/potentials/HertzViscoelastic.h"
#include "md/potentials/SpringDashpot.h"

namespace granagg::md {

/// A model with its parameters: what the engine holds (`Model` names the type for std::visit).
template <class M>
struct Contact {
  using Model = M;
  typename M::Params params;
};

/// THE LIST: every contact model granagg knows.
using ContactModel = std::variant<Contact<HertzViscoelastic>, Contact<SpringDashpot>>;

namespace detail {
template <std::size_t I = 0>
ContactModel contactModelNamed(const ContactConfig& c, double m_eff) {
  if constexpr (I == std::variant_size_v<ContactModel>) {
    throw std::invalid_argument("contact.model = \"" + c.model + "\" is not a contact model");
  } else {
    using M = typename std::variant_alternative_t<I, ContactModel>::Model;
    if (c.model == M::name) return Contact<M>{M::fromConfig(c, m_eff)};
    return contactModelNamed<I + 1>(c, m_eff);
  }
}
template <std::size_t... I>
std::string contactModelNames(std::index_sequence<I...>) {
  std::string s;
  ((s += (I ? ", \"" : "\"") +
         std::string(std::variant_alternative_t<I, ContactModel>::Model::name) + "\""),
   ...);
  return s;
}
template <std::size_t... I>
bool isContactModel(const std::string& name, std::index_sequence<I...>) {
  return ((name == std::variant_alternative_t<I, ContactModel>::Model::name) || ...);
}
}  // namespace detail

/// The model that contact.model names, with its parameters from `c`.
inline ContactModel makeContactModel(const ContactConfig& c, double m_eff) {
  return detail::contactModelNamed(c, m_eff);
}

/// The names contact.model accepts, quoted and comma-separated (for error messages).
inline std::string contactModelNames() {
  return detail::contactModelNames(std::make_index_sequence<std::variant_size_v<ContactModel>>{});
}

/// Whether `name` selects a contact model.
inline bool isContactModel(const std::string& name) {
  return detail::isContactModel(name,
                                std::make_index_sequence<std::variant_size_v<ContactModel>>{});
}

}  // namespace granagg::md
