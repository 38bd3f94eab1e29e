/* bcryptprimitives.dll for wine 8 (Debian 12's), which lacks it: Rust's standard library on
 * Windows (since Rust 1.78) takes its random numbers (HashMap seeds) from ProcessPrng in
 * bcryptprimitives.dll, a DLL every Windows 10 and 11 has. Wine 9 has it; this stand-in, put
 * next to the test host's .exe and used by the wine tests only (never shipped in an FMU), forwards
 * to RtlGenRandom (advapi32's SystemFunction036), which wine 8 has.
 *
 * x86_64-w64-mingw32-gcc -shared -o bcryptprimitives.dll bcryptprimitives.c -ladvapi32 */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len) {
    while (len > 0) {
        ULONG n = len > 0x10000000 ? 0x10000000 : (ULONG)len;
        if (!SystemFunction036(data, n)) return FALSE;
        data += n;
        len -= n;
    }
    return TRUE;
}
