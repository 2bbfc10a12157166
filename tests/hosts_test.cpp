// The hosts-file grammar of hosts.h: what parses, what it means, and every
// error with its FILE:LINE.
#include "hosts.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace {

std::vector<HostSpec> Parse(const std::string& text) {
  std::vector<HostSpec> hosts;
  std::string err;
  EXPECT_TRUE(ParseHosts(text, "h", &hosts, &err)) << err;
  return hosts;
}

std::string Error(const std::string& text) {
  std::vector<HostSpec> hosts;
  std::string err;
  EXPECT_FALSE(ParseHosts(text, "hosts.txt", &hosts, &err)) << text;
  return err;
}

TEST(Hosts, FullLine) {
  auto h = Parse("alice@node7.example.org:2222 slots=4 cmd=/opt/bin/radiosity\n");
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].user, "alice");
  EXPECT_EQ(h[0].name, "node7.example.org");
  EXPECT_EQ(h[0].port, 2222);
  EXPECT_EQ(h[0].slots, 4);
  EXPECT_EQ(h[0].cmd, "/opt/bin/radiosity");
  EXPECT_EQ(h[0].line, 1);
  EXPECT_FALSE(h[0].Local());
  EXPECT_EQ(FormatHost(h[0]), "alice@node7.example.org:2222 slots=4 cmd=/opt/bin/radiosity");
}

TEST(Hosts, DefaultsCommentsBlanksAndOrder) {
  auto h = Parse("# cluster\n\n  n1\t# one worker\nn2 cmd=~/rad slots=2   \r\n\t\nlocalhost slots=3\n");
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0].name, "n1");
  EXPECT_EQ(h[0].user, "");
  EXPECT_EQ(h[0].port, 0);
  EXPECT_EQ(h[0].slots, 1);
  EXPECT_EQ(h[0].cmd, "");
  EXPECT_EQ(h[0].line, 3);
  EXPECT_EQ(h[1].slots, 2);
  EXPECT_EQ(h[1].cmd, "~/rad");
  EXPECT_EQ(h[1].line, 4);
  EXPECT_TRUE(h[2].Local());
  EXPECT_EQ(h[2].slots, 3);
  EXPECT_EQ(FormatHost(h[0]), "n1 slots=1");
}

TEST(Hosts, Ipv6InBrackets) {
  auto h = Parse("[::1]:2200\nbob@[fe80::1%eth0]\n");
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0].name, "::1");
  EXPECT_EQ(h[0].port, 2200);
  EXPECT_EQ(h[1].name, "fe80::1%eth0");
  EXPECT_EQ(h[1].user, "bob");
  EXPECT_EQ(FormatHost(h[0]), "[::1]:2200 slots=1");
}

// Found by fuzz/hosts_fuzz: "[name]" without a ':' parsed as the name
// "name", which --dump-hosts printed without brackets, so that the output
// did not read back as the same host (here '%' is bad outside brackets).
TEST(Hosts, BracketsOnlyForIpv6) {
  EXPECT_EQ(Error("bob@[node1%eth0]\n"),
            "hosts.txt:1: brackets are for IPv6 addresses, not 'bob@[node1%eth0]'");
  EXPECT_EQ(Error("[node1]:22\n"), "hosts.txt:1: brackets are for IPv6 addresses, not '[node1]:22'");
  for (const char* text : {"[::1]:2200\n", "bob@[fe80::1%eth0] slots=3 cmd=/x\n"}) {
    auto h = Parse(text);
    ASSERT_EQ(h.size(), 1u);
    auto again = Parse(FormatHost(h[0]) + "\n");
    ASSERT_EQ(again.size(), 1u);
    EXPECT_EQ(FormatHost(again[0]), FormatHost(h[0]));
  }
}

TEST(Hosts, EmptyTextIsNoHosts) { EXPECT_TRUE(Parse("# nothing\n\n").empty()); }

TEST(Hosts, ErrorsNameFileAndLine) {
  EXPECT_EQ(Error("n1\nslots=2\n"), "hosts.txt:2: expected [user@]host[:port] before 'slots=2'");
  EXPECT_EQ(Error("@n1\n"), "hosts.txt:1: empty user name before '@' in '@n1'");
  EXPECT_EQ(Error("a;b@n1\n"), "hosts.txt:1: bad character ';' in user name 'a;b'");
  EXPECT_EQ(Error("bob@\n"), "hosts.txt:1: empty host name in 'bob@'");
  EXPECT_EQ(Error(":22\n"), "hosts.txt:1: empty host name in ':22'");
  EXPECT_EQ(Error("n$(id)\n"), "hosts.txt:1: bad character '$' in host name 'n$(id)'");
  EXPECT_EQ(Error("n1:\n"), "hosts.txt:1: bad port '' in 'n1:' (must be 1 to 65535)");
  EXPECT_EQ(Error("n1:0\n"), "hosts.txt:1: bad port '0' in 'n1:0' (must be 1 to 65535)");
  EXPECT_EQ(Error("n1:65536\n"), "hosts.txt:1: bad port '65536' in 'n1:65536' (must be 1 to 65535)");
  EXPECT_EQ(Error("n1:ssh\n"), "hosts.txt:1: bad port 'ssh' in 'n1:ssh' (must be 1 to 65535)");
  EXPECT_EQ(Error("::1\n"),
            "hosts.txt:1: write an IPv6 address in brackets, [addr] or [addr]:port, not '::1'");
  EXPECT_EQ(Error("[::1\n"), "hosts.txt:1: missing ']' after IPv6 address in '[::1'");
  EXPECT_EQ(Error("[::1]22\n"), "hosts.txt:1: expected ':port' after ']' in '[::1]22'");
  EXPECT_EQ(Error("\n\nn1 slots=0\n"), "hosts.txt:3: bad slots '0' (must be 1 to 256)");
  EXPECT_EQ(Error("n1 slots=257\n"), "hosts.txt:1: bad slots '257' (must be 1 to 256)");
  EXPECT_EQ(Error("n1 slots=-1\n"), "hosts.txt:1: bad slots '-1' (must be 1 to 256)");
  EXPECT_EQ(Error("n1 slots=2x\n"), "hosts.txt:1: bad slots '2x' (must be 1 to 256)");
  EXPECT_EQ(Error("n1 slots=2 slots=3\n"), "hosts.txt:1: slots= given twice");
  EXPECT_EQ(Error("n1 cmd=/a cmd=/b\n"), "hosts.txt:1: cmd= given twice");
  EXPECT_EQ(Error("n1 cmd=\n"), "hosts.txt:1: empty cmd= (leave it out to upload this binary)");
  EXPECT_EQ(Error("n1 max_slots=4\n"), "hosts.txt:1: unknown key 'max_slots' (expected slots= or cmd=)");
  EXPECT_EQ(Error("n1 4\n"), "hosts.txt:1: expected key=value, got '4'");
  EXPECT_EQ(Error("n1\x01\n"), "hosts.txt:1: control character in line");
  const std::string local =
      ": localhost forks workers on this machine without ssh, so it takes no user@ or :port "
      "(write 127.0.0.1 to use ssh to this machine)";
  EXPECT_EQ(Error("root@localhost\n"), "hosts.txt:1" + local);
  EXPECT_EQ(Error("# x\nlocalhost:22\n"), "hosts.txt:2" + local);
}

TEST(Hosts, ReadHostsFileErrors) {
  std::vector<HostSpec> hosts;
  std::string err;
  EXPECT_FALSE(ReadHosts("/nonexistent/hosts", &hosts, &err));
  EXPECT_EQ(err, "/nonexistent/hosts: No such file or directory");
  EXPECT_FALSE(ReadHosts("/dev/null", &hosts, &err));  // a device is not read at all
  EXPECT_EQ(err, "/dev/null: not a regular file");
}

}  // namespace
