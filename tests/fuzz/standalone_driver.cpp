// Drives LLVMFuzzerTestOneInput without libFuzzer (GCC builds): seeded random byte strings of
// every length around the packet sizes, plus bit-flipped valid packets. Usage: driver [runs].
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  const long runs = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 200000;
  std::mt19937_64 rng(0x5b410u);
  std::vector<std::uint8_t> buffer;
  for (long run = 0; run < runs; ++run) {
    buffer.resize(rng() % 110);
    for (auto& b : buffer) b = static_cast<std::uint8_t>(rng());
    if (run % 3 == 0) {
      // Mostly-valid packets: small finite floats, then a few flipped bits.
      for (std::size_t i = 0; i + 4 <= buffer.size(); i += 4) buffer[i] &= 0x3F;
      if (!buffer.empty()) buffer.back() &= 0x0F;
      const int flips = static_cast<int>(rng() % 3);
      for (int f = 0; f < flips && !buffer.empty(); ++f) {
        buffer[rng() % buffer.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      }
    }
    LLVMFuzzerTestOneInput(buffer.data(), buffer.size());
  }
  std::printf("fuzz driver: %ld inputs, no crash, no mismatch\n", runs);
  return 0;
}
