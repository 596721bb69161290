#include <vxf/io/AtomicFile.h>

#include <vxf/core/Error.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

using vxf::test::TempDir;

TEST_CASE("atomic writes leave all or nothing", "[io][atomic]")
{
    TempDir dir;
    const std::string target = dir.path("out.txt");

    vxf::writeAtomically(target, [](const std::string& tmp) { std::ofstream(tmp) << "first"; });
    CHECK(vxf::test::slurp(target) == "first");

    SECTION("a failing writer keeps the old file and leaves no temporary")
    {
        CHECK_THROWS_WITH(vxf::writeAtomically(target,
                              [](const std::string& tmp) {
                                  std::ofstream(tmp) << "half";
                                  throw vxf::Error("disk on fire");
                              }),
            "disk on fire");
        CHECK(vxf::test::slurp(target) == "first");
        CHECK(std::distance(std::filesystem::directory_iterator(dir.root()), {}) == 1);
    }
    SECTION("a failing writer of a new file leaves no file")
    {
        const std::string fresh = dir.path("new.txt");
        CHECK_THROWS(vxf::writeAtomically(fresh, [](const std::string&) { throw vxf::Error("no"); }));
        CHECK_FALSE(std::filesystem::exists(fresh));
    }
    SECTION("a missing directory is named")
    {
        CHECK_THROWS_WITH(vxf::writeAtomically(dir.path("nope/out.txt"), [](const std::string&) {}),
            Catch::Contains("directory") && Catch::Contains("does not exist"));
    }
}

namespace {
/// A child process that starts writing @a target and stops inside its writer; returns its pid
/// once the temporary exists.
pid_t writerStuckInside(const std::string& target, const std::filesystem::path& dir)
{
    const pid_t pid = ::fork();
    if (pid == 0) {
        vxf::writeAtomically(target, [](const std::string& tmp) {
            std::ofstream(tmp) << "half";
            for (;;) ::pause();
        });
        std::_Exit(0);
    }
    const auto temporaries = [&] {
        int n = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir)) {
            n += e.path().filename().string().find(std::to_string(pid)) != std::string::npos ? 1 : 0;
        }
        return n;
    };
    for (int i = 0; i < 500 && temporaries() == 0; ++i) ::usleep(10000);
    return pid;
}
} // namespace

TEST_CASE("a write removes the temporaries of killed writers of the same file, and only those", "[io][atomic]")
{
    TempDir dir;
    const std::string target = dir.path("out.vdb");
    const pid_t killed = writerStuckInside(target, dir.root());
    const pid_t alive = writerStuckInside(target, dir.root());
    ::kill(killed, SIGKILL); // no handler runs: its temporary stays behind
    ::waitpid(killed, nullptr, 0);
    vxf::test::spit(dir.path(".out.vdb.tmp-another_machine-1-0"), "a farm machine's, on a shared folder");
    vxf::test::spit(dir.path(".other.vdb.tmp-x-1-0"), "another file's");
    const auto names = [&] {
        std::vector<std::string> out;
        for (const auto& e : std::filesystem::directory_iterator(dir.root())) out.push_back(e.path().filename().string());
        std::sort(out.begin(), out.end());
        return out;
    };
    REQUIRE(names().size() == 4);

    vxf::writeAtomically(target, [](const std::string& tmp) { std::ofstream(tmp) << "whole"; });
    ::kill(alive, SIGKILL);
    ::waitpid(alive, nullptr, 0);
    CHECK(vxf::test::slurp(target) == "whole");
    const auto left = names();
    CHECK(left.size() == 4); // out.vdb, the live writer's, the other machine's, the other file's
    CHECK(std::count_if(left.begin(), left.end(),
              [&](const std::string& n) { return n.find("-" + std::to_string(killed) + "-") != std::string::npos; }) == 0);
    CHECK(std::count_if(left.begin(), left.end(),
              [&](const std::string& n) { return n.find("-" + std::to_string(alive) + "-") != std::string::npos; }) == 1);
}
