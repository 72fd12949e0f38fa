#pragma once
/// \file OutputPath.h
/// Checks a command makes before it computes anything: that its output can be written where the
/// user asked, so that a read-only or missing folder is refused in one line before the work (a
/// Smoluchowski solve, a fit, an MD run's set-up), not after it.
///
/// Design. Permission bits cannot answer the question (root ignores them, and a read-only file
/// system or a FUSE mount answers differently), so each check creates, and removes at once, a
/// uniquely named probe entry in the folder the output would go into. Nothing else is created: a
/// missing output folder stays missing until the command writes it. Every refusal is one line in
/// the style of common::FolderLock, naming the option:
/// `--out 'PATH': cannot create the folder (Permission denied)`.
#include <filesystem>
#include <string>

namespace granagg::common {

/// A file `path` is to be written (through a temporary name in its folder, then renamed). Throws
/// std::invalid_argument naming `option` when its folder does not exist, is not a folder, or does
/// not take a new file, or when `path` is a folder.
void checkOutputFile(const std::filesystem::path& path, const std::string& option = "--out");

/// A folder `folder` is to be written (created with its parents where missing). Throws
/// std::invalid_argument naming `option` when it is a file, when it exists and does not take a
/// new file, or when the nearest existing folder above it does not take a new folder.
void checkOutputFolder(const std::filesystem::path& folder, const std::string& option = "--out");

}  // namespace granagg::common
