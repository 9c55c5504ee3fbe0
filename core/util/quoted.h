// Text from outside (a client's name, a line of a user's file) quoted for a
// message or log line.
#pragma once

#include <string>
#include <string_view>

namespace lmd {

// `value` in single quotes, bytes outside printable ASCII (and the
// backslash) escaped as \xNN, cut after 80 characters ("..."): outside bytes
// must not forge log lines or flood a terminal.
std::string Quoted(std::string_view value);

}  // namespace lmd
