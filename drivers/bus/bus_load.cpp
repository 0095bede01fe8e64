#include "drivers/bus/bus_load.h"

namespace kuavo::drivers {

int classic_frame_bits_worst(int n, bool extended_id) {
  if (extended_id) return 8 * n + 67 + (54 + 8 * n - 1) / 4;
  return 8 * n + 47 + (34 + 8 * n - 1) / 4;
}

double classic_frame_time_us(int payload_bytes, bool extended_id, double bitrate_bps) {
  return classic_frame_bits_worst(payload_bytes, extended_id) * 1e6 / bitrate_bps;
}

double fd_frame_time_us(int n, bool extended_id, double nominal_bps, double data_bps) {
  // Nominal phase: SOF, ID (11 or 11+1+1+18), RRS/r1, IDE, FDF, res, BRS; after
  // the CRC: CRC delimiter, ACK slot + delimiter, EOF 7, IFS 3.
  const int arb_bits = extended_id ? 1 + 11 + 2 + 18 + 1 + 1 + 1 + 1 : 1 + 11 + 1 + 1 + 1 + 1 + 1;
  const int arb_stuff = (arb_bits - 1) / 4;
  const int tail_bits = 1 + 2 + 7 + 3;
  // Data phase: ESI, DLC 4, data, stuff count 4, CRC 17 (<= 16 bytes) or 21,
  // with a fixed stuff bit every 4 CRC bits plus dynamic stuffing before it.
  const int crc_bits = n <= 16 ? 17 : 21;
  const int data_bits = 1 + 4 + 8 * n;
  const int data_stuff = (data_bits - 1) / 4;
  const int fixed_stuff = (4 + crc_bits + 3) / 4;
  const double nominal_us = (arb_bits + arb_stuff + tail_bits) * 1e6 / nominal_bps;
  const double data_us = (data_bits + data_stuff + 4 + crc_bits + fixed_stuff) * 1e6 / data_bps;
  return nominal_us + data_us;
}

}  // namespace kuavo::drivers
