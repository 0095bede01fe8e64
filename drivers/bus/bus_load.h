// Worst-case CAN bus load. Bits per frame include the worst-case bit stuffing
// (Davis, Burns, Bril, Lukkien, "Controller Area Network (CAN) schedulability
// analysis: refuted, revisited and revised", Real-Time Systems 35, 2007, eq. 1)
// and the 3-bit interframe space. Start-up only (config check), but heap-free.
#pragma once

#include <cstdint>

namespace kuavo::drivers {

// The load every bus must stay below (issue 7): headroom for retransmissions
// after errors and for the start-up SDO traffic.
inline constexpr double kMaxBusLoad = 0.70;

// Classic CAN, 11-bit ID, n data bytes: 8n + 47 + floor((34 + 8n - 1) / 4).
// 29-bit ID: 8n + 67 + floor((54 + 8n - 1) / 4). 8 bytes, 11-bit ID -> 135 bit.
int classic_frame_bits_worst(int payload_bytes, bool extended_id);

// CAN FD: arbitration-phase bits at the nominal rate, data-phase bits at the
// data rate (BRS). Conservative: worst-case dynamic stuffing over the whole
// frame plus the fixed stuff bits of the FD CRC field. Returns microseconds.
double fd_frame_time_us(int payload_bytes, bool extended_id, double nominal_bps, double data_bps);

// Time one classic frame occupies the bus, microseconds.
double classic_frame_time_us(int payload_bytes, bool extended_id, double bitrate_bps);

}  // namespace kuavo::drivers
