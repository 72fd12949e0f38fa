#pragma once
/// \file FmtCompat.h
/// Lets libfmt-dev's fmt 9 parse the headers of Debian's liblammps-dev (LAMMPS 29 Sep 2021).
/// Include it before any LAMMPS header (md/lammps/LammpsApi.h does).
///
/// Why: LAMMPS's headers include "fmt/format.h", but liblammps-dev does not ship it (LAMMPS
/// bundles fmt 7 as `fmt::v7_lmp` inside liblammps.so). The only system fmt, fmt 9, parses them
/// except for one name: the variadic templates of Error and utils (error->all(FLERR, fmt, args...),
/// utils::logmesg(lmp, fmt, args...)) call `fmt::make_args_checked<Args...>`, which fmt 9 removed.
/// A qualified call with explicit template arguments must name a declared template when the
/// header is parsed, so it is declared here, and only declared: instantiating it is a link
/// error, as it must be, because those templates would pass fmt 9 types to functions that
/// liblammps.so compiled for fmt 7 (a different ABI). granagg therefore calls no LAMMPS function
/// that takes fmt types: error->all/one with a std::string message (the non-template overloads),
/// utils::logmesg with a std::string.
///
/// A LAMMPS that bundles its own fmt headers (a site's build from source) finds them first on
/// its include path; their fmt (7 or 8) still has make_args_checked and this header adds nothing.
#include <fmt/format.h>

#if FMT_VERSION >= 90000
FMT_BEGIN_NAMESPACE
/// fmt 8's signature (fmt/core.h): the argument store of a checked format call. Declared only.
template <typename... Args, typename S, typename Char = char>
auto make_args_checked(const S& format_str, const remove_reference_t<Args>&... args)
    -> format_arg_store<buffer_context<Char>, remove_reference_t<Args>...>;
FMT_END_NAMESPACE
#endif
