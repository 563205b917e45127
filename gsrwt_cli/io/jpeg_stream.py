"""Where a JPEG stream ends, found by walking its markers, whatever follows it in the file.

Phones append data after a JPEG's end-of-image marker (EOI, ``FF D9``): a "motion photo"
carries an MP4 video there (Google's ``MicroVideo``/``MotionPhoto``, Samsung's
``MotionPhoto_Data``), a multi-picture file (MPO) a second JPEG. The image is complete; only
its last bytes are not ``FF D9``. Searching the file for ``FF D9`` would not tell where the
image ends: an EXIF thumbnail before the image data ends with ``FF D9`` too, and a video after
it holds those two bytes anywhere.

:func:`jpeg_stream_end` walks the stream as a decoder reads it (ITU-T T.81, Annex B): from
the start-of-image marker, marker segments by their lengths (APPn, DQT, DHT, SOFn, ...), and
after each start-of-scan (SOS) the entropy-coded data up to the next marker (in which ``FF``
is always followed by a stuffed ``00`` or is a restart marker ``D0``-``D7``), until EOI.
Progressive files (several scans, tables between them) and restart intervals walk the same.
"""

from __future__ import annotations

import re

#: A marker inside or after entropy-coded data: ``FF`` then a code that is not a stuffed
#: ``00``, a restart marker ``D0``-``D7`` (part of the scan) or another fill byte ``FF``.
_NEXT_MARKER = re.compile(rb"\xff[^\x00\xd0-\xd7\xff]")
#: Markers without a length field: TEM, RST0-7, SOI (EOI ends the walk).
_STANDALONE = frozenset({0x01, 0xD8, *range(0xD0, 0xD8)})
_SOS, _EOI = 0xDA, 0xD9


def jpeg_stream_end(data: bytes | bytearray | memoryview) -> int | None:
    """The offset just past the EOI marker of the JPEG stream that starts ``data``.

    None when ``data`` ends before the stream does (a truncated file), or does not start
    with a JPEG's start-of-image marker. Bytes after the EOI are not looked at. A stream
    that is damaged but not short (a segment length below 2, bytes between segments) is
    walked on from the next marker, as a decoder resynchronises; the decoder then judges it.
    Costs one scan of the entropy-coded data in C (a regular-expression search per scan).
    """
    data = bytes(data) if not isinstance(data, bytes) else data
    if data[:2] != b"\xff\xd8":
        return None
    size, position = len(data), 2
    while True:
        if position >= size:
            return None
        if data[position] != 0xFF:  # not a marker where one must be: resynchronise
            found = _NEXT_MARKER.search(data, position)
            if found is None:
                return None
            position = found.start()
        while position < size and data[position] == 0xFF:  # fill bytes before a marker code
            position += 1
        if position >= size:
            return None
        code = data[position]
        position += 1
        if code == _EOI:
            return position
        if code in _STANDALONE or code == 0x00:
            continue
        if position + 2 > size:
            return None
        length = int.from_bytes(data[position:position + 2], "big")
        if length < 2:  # a bogus length: the decoder refuses it; walk on to the next marker
            continue
        position += length
        if position > size:
            return None
        if code == _SOS:  # the scan's entropy-coded data runs to the next marker
            found = _NEXT_MARKER.search(data, position)
            if found is None:
                return None
            position = found.start()


#: What starts the payload of an APP2 segment that carries (a chunk of) an ICC profile.
_ICC_SIGNATURE = b"ICC_PROFILE\x00"
_APP0, _APP2 = 0xE0, 0xE2


def header_segments(data: bytes) -> list[tuple[int, int, int]]:
    """``(code, start, end)`` of each marker segment before the first scan (``start`` at its
    ``FF``); empty for data that is not a JPEG or whose header is cut short."""
    if data[:2] != b"\xff\xd8":
        return []
    segments, position, size = [], 2, len(data)
    while position + 4 <= size and data[position] == 0xFF:
        code = data[position + 1]
        if code in _STANDALONE or code in (0xFF, 0x00):
            position += 1 if code == 0xFF else 2
            continue
        length = int.from_bytes(data[position + 2:position + 4], "big")
        end = position + 2 + length
        if length < 2 or end > size:
            break
        segments.append((code, position, end))
        if code == _SOS:
            break
        position = end
    return segments


def icc_segments(data: bytes) -> bytes:
    """The APP2 ``ICC_PROFILE`` segments of a JPEG's header, whole and in order (a profile
    over 64 KB is split over several: ICC.1 Annex B.4); empty if it has none."""
    return b"".join(data[start:end] for code, start, end in header_segments(data)
                    if code == _APP2 and data[start + 4:start + 4 + len(_ICC_SIGNATURE)]
                    == _ICC_SIGNATURE)


#: The colour space signature of an ICC profile (its header's bytes 16-19, ICC.1 7.2.6) that
#: describes an image of each number of channels (a JPEG's components, a decoded image's).
ICC_COLOUR_SPACES = {1: b"GRAY", 3: b"RGB ", 4: b"CMYK"}
#: Start-of-frame markers: SOF0-3, 5-7, 9-11, 13-15 (C4, C8 and CC are other markers).
_SOF = frozenset({*range(0xC0, 0xC4), *range(0xC5, 0xC8), *range(0xC9, 0xCC),
                  *range(0xCD, 0xD0)})


def jpeg_components(data: bytes) -> int | None:
    """How many colour components a JPEG's frame has (1 grey, 3 YCbCr or RGB, 4 CMYK or
    YCCK), from its first start-of-frame segment; None if there is none before the scan."""
    for code, start, end in header_segments(data):
        if code in _SOF and end >= start + 10:
            return data[start + 9]
    return None


def icc_colour_space(segments: bytes) -> bytes | None:
    """The colour space signature (``b"RGB "``, ``b"GRAY"``, ``b"CMYK"``, ...) of the ICC
    profile in ``segments`` (as :func:`icc_segments` gives them): bytes 16-19 of the chunk
    numbered 1; None if there is no such chunk or it is too short to say."""
    position, prefix = 0, 4 + len(_ICC_SIGNATURE)  # marker, length, signature
    while position + prefix + 2 <= len(segments):
        end = position + 2 + int.from_bytes(segments[position + 2:position + 4], "big")
        if segments[position + prefix] == 1:  # the chunk's sequence number
            space = segments[position + prefix + 2 + 16:position + prefix + 2 + 20]
            return space if len(space) == 4 and position + prefix + 2 + 20 <= end else None
        position = end
    return None


def with_segments(jpeg: bytes, segments: bytes) -> bytes:
    """``jpeg`` with marker ``segments`` inserted into its header: after its JFIF APP0
    segment, which must come first, or else right after its start-of-image marker."""
    if not segments:
        return jpeg
    header = header_segments(jpeg)
    at = header[0][2] if header and header[0][0] == _APP0 else 2
    whole = memoryview(jpeg)
    return b"".join((whole[:at], segments, whole[at:]))  # one copy of the image data
