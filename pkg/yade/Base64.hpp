// Base64 for the fabric's bytes in O.save's archives (binary .yade.gz and XML alike).
#pragma once
#include <stdexcept>
#include <string>

namespace woven::yadeplugin {

inline std::string base64Encode(const std::string& in)
{
	static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
	std::string        out;
	out.reserve((in.size() + 2) / 3 * 4);
	std::size_t i = 0;
	for (; i + 2 < in.size(); i += 3) {
		const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8 | (unsigned char)in[i + 2];
		out += k[v >> 18], out += k[(v >> 12) & 63], out += k[(v >> 6) & 63], out += k[v & 63];
	}
	if (i + 1 == in.size()) {
		const unsigned v = (unsigned char)in[i] << 16;
		out += k[v >> 18], out += k[(v >> 12) & 63], out += "==";
	} else if (i + 2 == in.size()) {
		const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8;
		out += k[v >> 18], out += k[(v >> 12) & 63], out += k[(v >> 6) & 63], out += '=';
	}
	return out;
}

inline std::string base64Decode(const std::string& in)
{
	auto val = [](char c) -> int {
		if (c >= 'A' && c <= 'Z') return c - 'A';
		if (c >= 'a' && c <= 'z') return c - 'a' + 26;
		if (c >= '0' && c <= '9') return c - '0' + 52;
		if (c == '+') return 62;
		if (c == '/') return 63;
		return -1;
	};
	if (in.size() % 4) throw std::invalid_argument("snapshot: base64 length not a multiple of 4");
	std::string out;
	out.reserve(in.size() / 4 * 3);
	for (std::size_t i = 0; i < in.size(); i += 4) {
		int v[4];
		int pad = 0;
		for (int j = 0; j < 4; ++j) {
			const char c = in[i + j];
			if (c == '=' && i + 4 == in.size() && j >= 2) {
				v[j] = 0, ++pad;
				continue;
			}
			v[j] = val(c);
			if (v[j] < 0 || pad) throw std::invalid_argument("snapshot: not base64");
		}
		const unsigned x = unsigned(v[0]) << 18 | unsigned(v[1]) << 12 | unsigned(v[2]) << 6 | unsigned(v[3]);
		out += char(x >> 16);
		if (pad < 2) out += char((x >> 8) & 255);
		if (pad < 1) out += char(x & 255);
	}
	return out;
}

} // namespace woven::yadeplugin
