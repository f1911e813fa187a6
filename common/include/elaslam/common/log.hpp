// SPDX-License-Identifier: Apache-2.0
// Log lines with a priority the journal understands. A program run by systemd has its
// stderr connected to the journal, and systemd says so in $JOURNAL_STREAM
// ("<st_dev>:<st_ino>" of that stream, systemd.exec(5)); then each line starts with
// sd-daemon(3)'s "<N>" prefix (SD_ERR "<3>", SD_WARNING "<4>", SD_INFO "<6>"), which
// journald strips and keeps as the entry's priority, so `journalctl -p warning -u
// 'elaslam-*'` shows refusals, faults and fatal errors only. On a terminal, in a
// file, in a pipe (tests, run_team.sh): plain text, as before.
//
// Which priority: err for what ends the program (a bad configuration, LCM that cannot
// be opened, an exception out of main); warning for refused messages, faults and
// what the node did about them (started fresh, a save that failed); info for the rest.
#pragma once

#include <cstdio>

namespace elaslam::log {

/// syslog(3)'s levels, the numbers of sd-daemon(3)'s prefixes.
enum class Priority { kErr = 3, kWarning = 4, kNotice = 5, kInfo = 6, kDebug = 7 };

/// Whether `f` writes to the journal: $JOURNAL_STREAM is set and names the device and
/// inode of f's descriptor. Read every call (no caching: cheap, and tests set it).
bool is_journal(std::FILE* f);

/// "<N>" for `p` when `f` is the journal, else "". A static string.
const char* prefix(std::FILE* f, Priority p);

/// printf to `f`, each line of the text led by prefix(f, p). The text should end with
/// a newline. Formats into a fixed buffer (4 KB, longer text is cut): no allocation.
void print(std::FILE* f, Priority p, const char* format, ...) __attribute__((format(printf, 3, 4)));

}  // namespace elaslam::log
