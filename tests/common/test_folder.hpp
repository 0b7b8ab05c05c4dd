// test_folder.hpp - a fresh, empty scratch folder for the running GoogleTest test.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace dqj::test {

/// "<temp>/<prefix>_<pid>_<test name>", emptied and created. The pid keeps parallel ctest
/// processes apart; a parameterised test's "Name/Param" becomes "Name_Param", one folder, so
/// removing it leaves nothing behind.
inline std::filesystem::path freshTestFolder(const std::string& prefix) {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()) + "_" + name);
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    return folder;
}

}  // namespace dqj::test
