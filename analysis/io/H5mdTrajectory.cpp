#include "analysis/io/H5mdTrajectory.h"

#include "common/H5mdReader.h"

namespace granagg::analysis {

struct H5mdTrajectory::Impl {
  common::H5mdReader reader;
  std::size_t cursor = 0;
  std::map<std::string, std::string> params;
  Impl(const std::string& path, const std::string& group) : reader(path, group) {
    for (auto& [k, v] : reader.parameters()) params.emplace(k, v);
  }
};

H5mdTrajectory::H5mdTrajectory(const std::string& path, const std::string& group)
    : m_impl(std::make_unique<Impl>(path, group)) {}
H5mdTrajectory::~H5mdTrajectory() = default;

bool H5mdTrajectory::next(Frame& f) {
  Impl& m = *m_impl;
  if (m.cursor >= m.reader.frames()) return false;
  m.reader.readFrame(m.cursor, f);
  ++m.cursor;
  return true;
}

std::size_t H5mdTrajectory::frameCountHint() const { return m_impl->reader.frames(); }
const std::map<std::string, std::string>& H5mdTrajectory::parameters() const {
  return m_impl->params;
}
const std::string& H5mdTrajectory::path() const { return m_impl->reader.path(); }
std::size_t H5mdTrajectory::size() const { return m_impl->reader.size(); }

}  // namespace granagg::analysis
