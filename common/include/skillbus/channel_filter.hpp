// A kernel filter on a udpm:// socket that drops whole LCM messages of channels this
// process did not subscribe to, before they wake it.
//
// LCM's UDP multicast delivers every datagram of a group and port to every process on it;
// each then reads and drops what it did not subscribe to. Under lockstep a frame carries
// a dozen messages (the physics' state, the clock, ticks, progress), so every process was
// woken several times a frame for messages it never wanted: on 2 cores that CPU comes out
// of the frame (docs/transport.md, "Channel filters"). The filter (classic BPF, attached
// with SO_ATTACH_FILTER, run by the kernel as the datagram is queued) keeps:
//   - a short message ("LC02") whose channel is one of `channels`;
//   - everything else but a well-formed short message of another channel: fragments of
//     large messages ("LC03": only the first names its channel), and whatever is no LCM
//     message or has a malformed channel (empty, unterminated, over 63 characters), which
//     the reader then counts as bad input, as without a filter.
// The reader still checks every channel itself: the filter only saves wake-ups.
#pragma once

#include <string>
#include <vector>

namespace skillbus {

// Attaches (or replaces) the filter on `fd` for exactly `channels`. False, with `why`,
// when the kernel refuses it or the program would be too long: the socket then takes
// every datagram, as without a filter.
bool attach_channel_filter(int fd, const std::vector<std::string>& channels, std::string& why);

// Removes the filter: the socket takes every datagram again.
void detach_channel_filter(int fd);

}  // namespace skillbus
