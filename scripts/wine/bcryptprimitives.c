/* A stand-in for Windows's bcryptprimitives.dll, for Wine releases before 8.13, which lack
 * it: Rust's standard library takes its random bytes (the keys of HashMap's hasher) from
 * that DLL's ProcessPrng, and a program that cannot load it exits before main. Built by
 * scripts/setup with mingw-w64 into the project's Wine prefix; never shipped. */
#include <windows.h>
#include <ntsecapi.h>

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len)
{
    while (len > 0) {
        ULONG chunk = len > 0x40000000 ? 0x40000000 : (ULONG)len;
        if (!RtlGenRandom(data, chunk))
            return FALSE;
        data += chunk;
        len -= chunk;
    }
    return TRUE;
}
