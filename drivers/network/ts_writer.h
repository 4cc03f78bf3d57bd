#pragma once
// Two H.264 camera streams in one MPEG-TS multiplex, written to a URL with libavformat
// (udp://host:port, tcp://host:port, or a file path).
//
// Why MPEG-TS over UDP: it is the transport FFmpeg's muxer and demuxer handle most robustly on a
// lossy link. A lost datagram costs the 188-byte TS packets in it and the demuxer resynchronises
// on the next one (continuity counters tell it what was lost), whereas RTP needs an SDP exchanged
// out of band and one port per camera, and TCP turns loss into stalls, which a live VO cannot
// afford. Both cameras share one mux (PIDs 0x100 and 0x101), so they arrive over one socket in
// capture order. Each access unit is written as one PES packet with its length (so the receiver
// can hand it on the moment it is complete instead of waiting for the next one) and flushed at
// once; the sensor time rides inside the access unit (frame_stamp.h), the TS clock is derived from
// it (90 kHz from the first frame).

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>

namespace voca::network {

class StereoTsWriter {
 public:
  // Opens the output. For udp:// URLs without pkt_size, datagrams carry 7 TS packets (1316 bytes,
  // below any Ethernet MTU). Throws InputError for a bad URL, RuntimeFailure when libavformat fails.
  // stop_requested ends a blocking open (tcp://...?listen=1 waits for the receiver) with InputError.
  StereoTsWriter(const std::string& url, int width, int height, std::function<bool()> stop_requested = {});
  ~StereoTsWriter();
  StereoTsWriter(const StereoTsWriter&) = delete;
  StereoTsWriter& operator=(const StereoTsWriter&) = delete;

  // One access unit (Annex B) of `camera` (0 or 1) at t_ns; both cameras' frames must be written in
  // capture order.
  void write(int camera, std::span<const std::uint8_t> access_unit, std::int64_t t_ns, bool keyframe);
  // Writes the trailer and closes the output (also done by the destructor, without errors).
  void finish();

  std::int64_t bytesWritten() const;
  const std::string& url() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::network
