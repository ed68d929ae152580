// Force-included (`-include`) into the C++ that `scripts/wheel --glibc X.Y` compiles with zig.
//
// chemfiles 0.10 bundles fmt 6.1, which in C++11 declares its own `fmt::char8_t` (an enum) and
// asks for `std::char_traits<fmt::char8_t>`. libc++ from LLVM 19 on (zig's C++ library) has no
// generic `std::char_traits` template any more, only the standard character types, so every
// chemfiles source fails with "implicit instantiation of undefined template
// 'std::char_traits<fmt::char8_t>'". This header declares fmt's enum the way fmt 6 does (same
// name, namespace and underlying type; an opaque declaration) and gives it the traits of a
// byte-sized character. GCC's libstdc++ still has the generic template, so the default build
// does not need it.
#pragma once
#ifdef __cplusplus
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <cwchar>
#include <string>

#ifndef __cpp_char8_t
namespace fmt {
inline namespace v6 {
enum char8_t : unsigned char;
}
}  // namespace fmt

namespace std {
template <>
struct char_traits<fmt::v6::char8_t> {
    using char_type = fmt::v6::char8_t;
    using int_type = unsigned int;
    using off_type = streamoff;
    using pos_type = streampos;
    using state_type = mbstate_t;

    static void assign(char_type& to, const char_type& from) noexcept { to = from; }
    static bool eq(char_type a, char_type b) noexcept { return a == b; }
    static bool lt(char_type a, char_type b) noexcept {
        return static_cast<unsigned char>(a) < static_cast<unsigned char>(b);
    }
    static int compare(const char_type* a, const char_type* b, size_t count) {
        return count == 0 ? 0 : memcmp(a, b, count);
    }
    static size_t length(const char_type* text) {
        size_t count = 0;
        while (static_cast<unsigned char>(text[count]) != 0) {
            ++count;
        }
        return count;
    }
    static const char_type* find(const char_type* text, size_t count, const char_type& wanted) {
        for (size_t i = 0; i < count; ++i) {
            if (text[i] == wanted) {
                return text + i;
            }
        }
        return nullptr;
    }
    static char_type* move(char_type* to, const char_type* from, size_t count) {
        return count == 0 ? to : static_cast<char_type*>(memmove(to, from, count));
    }
    static char_type* copy(char_type* to, const char_type* from, size_t count) {
        return count == 0 ? to : static_cast<char_type*>(memcpy(to, from, count));
    }
    static char_type* assign(char_type* to, size_t count, char_type value) {
        return count == 0 ? to : static_cast<char_type*>(memset(to, value, count));
    }
    static char_type to_char_type(int_type value) noexcept { return char_type(value); }
    static int_type to_int_type(char_type value) noexcept { return int_type(value); }
    static bool eq_int_type(int_type a, int_type b) noexcept { return a == b; }
    static int_type eof() noexcept { return static_cast<int_type>(EOF); }
    static int_type not_eof(int_type value) noexcept { return value == eof() ? 0 : value; }
};
}  // namespace std
#endif
#endif
