"""A photo's metadata carried to its output: the input's EXIF, cleaned, and a record of what
gsrwt did in XMP, put into the bytes an encoder made (never a second encode: the pixels stay
exactly the encoder's).

Reading (:func:`photo_exif`): the EXIF block is found in the bytes already read for decoding,
no read of its own: a JPEG's APP1 ``Exif`` segment, a PNG's ``eXIf`` chunk before its pixels,
a WebP's ``EXIF`` chunk, a TIFF's own first IFD. Its tags are parsed by Pillow
(``Image.Exif``, the parser gsrwt already uses for EXIF focal lengths and orientation;
``benchmarks/bench_exif.py`` measured it robust on 3000 damaged blocks) into a
:class:`PhotoExif` of plain tags, without what no longer describes the output:

- the thumbnail (IFD1) and the maker's private notes (``MakerNote``: a preview of the stored
  photo in many makes, and offsets into the camera's own file that moving it breaks);
- how the input's pixels were stored (TIFF layout tags: strips, tiles, compression, samples,
  YCbCr subsampling), and the other containers (XMP, IPTC, Photoshop, ICC profile) inside it;
- positions in the input's pixels (``SubjectArea``, ``SubjectLocation``).

Everything else (make, model, lens, dates and times, GPS, exposure, focal length, copyright,
private tags) is kept. Writing (:func:`with_metadata`) sets ``Orientation`` to 1 (the output
is upright as stored), ``PixelXDimension``/``PixelYDimension`` (and ``ImageWidth``/
``ImageLength`` where the input had them) to the output's size, and serializes by Pillow
(``Image.Exif.tobytes``), which writes IFD0 and its Exif, GPS and Interoperability IFDs, no
IFD1. Where each format keeps them:

=====  ======================================  ===============================================
JPEG   APP1 ``Exif``, after the JFIF APP0      APP1 ``http://ns.adobe.com/xap/1.0/`` (XMP)
PNG    ``eXIf`` chunk, after IHDR              ``iTXt`` ``XML:com.adobe.xmp``, after IHDR
WebP   ``EXIF`` chunk (extended format VP8X)   ``XMP`` chunk (VP8X flags say both)
TIFF   the file's IFD0, Exif and GPS IFDs      tag 700 (XMP) in IFD0
=====  ======================================  ===============================================

A JPEG's EXIF segment holds at most 65,527 bytes of tags; a larger block (possible only from
a PNG, WebP or TIFF input) does not fit: :class:`MetadataError`.
"""

from __future__ import annotations

import struct
import warnings
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any
from xml.sax.saxutils import quoteattr

from .jpeg_stream import header_segments, with_segments

#: EXIF's own prefix of its block in a JPEG's APP1 segment.
EXIF_PREFIX = b"Exif\x00\x00"
#: The namespace of XMP in a JPEG's APP1 segment (XMP Specification Part 3, 1.1.3).
XMP_JPEG_PREFIX = b"http://ns.adobe.com/xap/1.0/\x00"
#: The iTXt keyword of XMP in a PNG (XMP Specification Part 3, 1.1.5).
XMP_PNG_KEYWORD = b"XML:com.adobe.xmp"
#: The XML namespace of the properties gsrwt records, and its prefix.
GSRWT_NAMESPACE = "urn:gsrwt:xmp:1.0#"
GSRWT_PREFIX = "gsrwt"

_ORIENTATION, _IMAGE_WIDTH, _IMAGE_LENGTH = 0x0112, 0x0100, 0x0101
_EXIF_IFD, _GPS_IFD, _INTEROP_IFD = 0x8769, 0x8825, 0xA005
_PIXEL_X, _PIXEL_Y = 0xA002, 0xA003
_XMP_TAG = 700
#: IFD0 tags left out: how the input's pixels are stored (TIFF 6.0's baseline and extension
#: layout tags, the old JPEG thumbnail pointers), and other metadata containers (XMP, IPTC,
#: Photoshop, ICC profile). ImageWidth and ImageLength are updated instead where present.
DROPPED_IFD0 = frozenset({
    0x00FE, 0x00FF, 0x0102, 0x0103, 0x0106, 0x0107, 0x0108, 0x0109, 0x010A, 0x0111,
    0x0115, 0x0116, 0x0117, 0x0118, 0x0119, 0x011C, 0x0122, 0x0123, 0x0124, 0x0125,
    0x012D, 0x013D, 0x0140, 0x0141, 0x0142, 0x0143, 0x0144, 0x0145, 0x014A, 0x014C,
    0x0152, 0x0153, 0x0154, 0x0155, 0x015B, *range(0x0200, 0x020A), 0x0212,
    _XMP_TAG, 0x83BB, 0x8649, 0x8773,
})
#: Exif IFD tags left out: the maker's notes, and positions in the input's pixels.
DROPPED_EXIF = frozenset({0x927C, 0x9214, 0xA214})


class MetadataError(Exception):
    """Metadata that cannot be written into an output (too large for its format, an
    encoder's output of a shape not expected), or :class:`DamagedExifError`; the message
    says which."""


class DamagedExifError(MetadataError):
    """An EXIF block Pillow cannot parse, or whose values it read but cannot write."""


@dataclass(frozen=True)
class PhotoExif:
    """A photo's EXIF tags, cleaned (module docstring), as Pillow reads their values:
    ``ifd0``, ``exif`` (the Exif IFD), ``gps`` and ``interop``, tag number to value;
    ``big_endian``: the input's byte order, kept. Small and picklable."""

    ifd0: dict[int, Any]
    exif: dict[int, Any] = field(default_factory=dict)
    gps: dict[int, Any] = field(default_factory=dict)
    interop: dict[int, Any] = field(default_factory=dict)
    big_endian: bool = False


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


def _png_chunks(data: bytes) -> list[tuple[bytes, int, int]]:
    """``(type, start, end)`` of a PNG's chunks up to its first IDAT (``start`` at the length
    field, ``end`` past the CRC); those before a damaged or cut length only."""
    chunks, position = [], 8
    while position + 12 <= len(data):
        length = int.from_bytes(data[position:position + 4], "big")
        kind = data[position + 4:position + 8]
        end = position + 12 + length
        if length > 0x7FFFFFFF or end > len(data) or kind == b"IDAT":
            break
        chunks.append((kind, position, end))
        position = end
    return chunks


def _riff_chunks(data: bytes) -> list[tuple[bytes, memoryview]]:
    """``(fourcc, payload)`` of a WebP's chunks, those before a cut one; the payloads are
    views of ``data``, not copies."""
    chunks, position, whole = [], 12, memoryview(data)
    end = min(len(data), 8 + int.from_bytes(data[4:8], "little"))
    while position + 8 <= end:
        size = int.from_bytes(data[position + 4:position + 8], "little")
        if position + 8 + size > end:
            break
        chunks.append((data[position:position + 4], whole[position + 8:position + 8 + size]))
        position += 8 + size + (size & 1)
    return chunks


def exif_block(data: bytes) -> bytes | None:
    """The EXIF block (a TIFF structure, with or without its ``Exif`` prefix) of an image
    file's bytes, or None: a JPEG's first APP1 ``Exif`` segment, a PNG's ``eXIf`` chunk
    before its pixels, a WebP's ``EXIF`` chunk, a TIFF file itself."""
    if data[:3] == b"\xff\xd8\xff":
        for code, start, end in header_segments(data):
            if code == 0xE1 and data[start + 4:start + 10] == EXIF_PREFIX:
                return data[start + 4:end]
        return None
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        for kind, start, end in _png_chunks(data):
            if kind == b"eXIf":
                return data[start + 8:end - 4]
        return None
    if data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        return next((bytes(payload) for fourcc, payload in _riff_chunks(data)
                     if fourcc == b"EXIF"), None)
    if data[:4] in (b"II*\x00", b"MM\x00*"):
        return data
    return None


def photo_exif(data: bytes) -> PhotoExif | None:
    """The cleaned EXIF (:class:`PhotoExif`) of an image file's bytes (:func:`exif_block`),
    or None when it has none, or nothing but an orientation. Raises :class:`DamagedExifError`
    for a block Pillow cannot parse; tags Pillow skips as damaged (it warns) are left out.
    The header only: 0.5-1.6 ms for a camera's EXIF, and Pillow's writer about 1 ms at the
    output; a 12 MP JPEG rectified with and without metadata took 510 and 506 ms (medians of
    12, one process, on a busy 2-core machine)."""
    block = exif_block(data)
    if block is None:
        return None
    from PIL import Image  # Pillow only when an image is read

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "Possibly corrupt EXIF data", ...
            exif = Image.Exif()
            exif.load(block)
            ifd0 = {tag: value for tag, value in exif.items()
                    if tag not in DROPPED_IFD0 and tag not in (_EXIF_IFD, _GPS_IFD)}
            sub = exif.get_ifd(_EXIF_IFD) if _EXIF_IFD in exif else {}
            interop = exif.get_ifd(_INTEROP_IFD) if _INTEROP_IFD in sub else {}
            sub = {tag: value for tag, value in sub.items()
                   if tag not in DROPPED_EXIF and tag != _INTEROP_IFD}
            gps = dict(exif.get_ifd(_GPS_IFD)) if _GPS_IFD in exif else {}
            big_endian = exif.endian == ">"
    except Exception as error:  # noqa: BLE001 - a third-party parser of untrusted bytes
        raise DamagedExifError(f"damaged EXIF ({type(error).__name__})") from None
    if not (set(ifd0) - {_ORIENTATION} or sub or gps):
        return None
    return PhotoExif(ifd0, sub, gps, dict(interop), big_endian)


# --------------------------------------------------------------------------------------------
# What is written
# --------------------------------------------------------------------------------------------


def _output_tags(photo: PhotoExif, size: tuple[int, int]) -> tuple[dict[int, Any], dict]:
    """IFD0's tags and the Exif IFD of the output: orientation 1, the output's size."""
    width, height = size
    ifd0 = {**photo.ifd0, _ORIENTATION: 1}
    if _IMAGE_WIDTH in ifd0 or _IMAGE_LENGTH in ifd0:
        ifd0[_IMAGE_WIDTH], ifd0[_IMAGE_LENGTH] = width, height
    sub: dict[int, Any] = {**photo.exif, _PIXEL_X: width, _PIXEL_Y: height}
    if photo.interop:
        sub[_INTEROP_IFD] = dict(photo.interop)
    return ifd0, sub


def exif_bytes(photo: PhotoExif, size: tuple[int, int]) -> bytes:
    """The output's EXIF block, with its ``Exif`` prefix: ``photo``'s tags with orientation 1
    and the output's ``size`` (``(width, height)``), IFD0, Exif, GPS and Interoperability
    IFDs serialized by Pillow. Raises :class:`DamagedExifError` if Pillow cannot write them."""
    from PIL import Image

    ifd0, sub = _output_tags(photo, size)
    exif = Image.Exif()
    exif.endian = ">" if photo.big_endian else "<"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for tag, value in ifd0.items():
                exif[tag] = value
            exif[_EXIF_IFD] = sub
            if photo.gps:
                exif[_GPS_IFD] = dict(photo.gps)
            return exif.tobytes()
    except Exception as error:  # noqa: BLE001 - values of untrusted bytes, Pillow's writer
        raise DamagedExifError(f"EXIF that cannot be written ({type(error).__name__})") from None


def xmp_packet(record: Mapping[str, str]) -> bytes:
    """An XMP packet (UTF-8, read-only: no padding) of simple properties in gsrwt's namespace
    (:data:`GSRWT_NAMESPACE`, prefix ``gsrwt``): ``record`` maps a property's name (an XML
    name) to its text."""
    properties = "".join(f"\n   {GSRWT_PREFIX}:{name}={quoteattr(text)}"
                         for name, text in record.items())
    return (
        '<?xpacket begin="\ufeff" id="W5M0MpCehiHzreSzNTczkc9d"?>\n'
        '<x:xmpmeta xmlns:x="adobe:ns:meta/">\n'
        ' <rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">\n'
        f'  <rdf:Description rdf:about=""\n   xmlns:{GSRWT_PREFIX}="{GSRWT_NAMESPACE}"'
        f"{properties}/>\n"
        " </rdf:RDF>\n"
        "</x:xmpmeta>\n"
        '<?xpacket end="r"?>'
    ).encode()


# --------------------------------------------------------------------------------------------
# Into each format
# --------------------------------------------------------------------------------------------

#: The largest payload of a JPEG marker segment (its length field counts itself).
_SEGMENT_PAYLOAD = 65533


def _jpeg_segment(code: int, payload: bytes, what: str) -> bytes:
    if len(payload) > _SEGMENT_PAYLOAD:
        raise MetadataError(f"{what} of {len(payload)} bytes does not fit a JPEG segment "
                            f"(at most {_SEGMENT_PAYLOAD})")
    return bytes((0xFF, code)) + struct.pack(">H", len(payload) + 2) + payload


def jpeg_segments(size: tuple[int, int], photo: PhotoExif | None,
                  record: Mapping[str, str] | None) -> bytes:
    """The APP1 segments of a JPEG of ``size`` that carry ``photo``'s EXIF
    (:func:`exif_bytes`) and ``record`` (:func:`xmp_packet`), to go after its JFIF header
    (:func:`~gsrwt_cli.io.jpeg_stream.with_segments`, which an encoder's caller may use to
    insert them with other segments at once); raises as :func:`with_metadata` does."""
    segments = b""
    if photo is not None:
        segments += _jpeg_segment(0xE1, exif_bytes(photo, size), "the EXIF")
    if record:
        segments += _jpeg_segment(0xE1, XMP_JPEG_PREFIX + xmp_packet(record),
                                  "the XMP packet")
    return segments


def _png_chunk(kind: bytes, payload: bytes) -> bytes:
    return (struct.pack(">I", len(payload)) + kind + payload
            + struct.pack(">I", zlib.crc32(kind + payload)))


def _with_png(png: bytes, exif: bytes | None, xmp: bytes | None) -> bytes:
    chunks = _png_chunks(png)
    if not chunks or chunks[0][0] != b"IHDR":
        raise MetadataError("the encoder's PNG does not start with IHDR")
    added = b""
    if exif is not None:
        added += _png_chunk(b"eXIf", exif[len(EXIF_PREFIX):])
    if xmp is not None:  # uncompressed iTXt, no language, no translated keyword
        added += _png_chunk(b"iTXt", XMP_PNG_KEYWORD + b"\x00\x00\x00\x00\x00" + xmp)
    at, whole = chunks[0][2], memoryview(png)
    return b"".join((whole[:at], added, whole[at:]))  # one copy of the image data


_VP8X_ALPHA, _VP8X_EXIF, _VP8X_XMP = 0x10, 0x08, 0x04


def _riff_chunk(fourcc: bytes, payload: bytes | memoryview) -> list[bytes | memoryview]:
    return [fourcc, struct.pack("<I", len(payload)), payload, b"\x00" * (len(payload) & 1)]


def _with_webp(webp: bytes, exif: bytes | None, xmp: bytes | None,
               size: tuple[int, int]) -> bytes:
    """A WebP in the extended format (a ``VP8X`` chunk first, its flags saying what follows)
    with ``EXIF`` and ``XMP`` chunks after the image's (WebP Container Specification)."""
    if webp[:4] != b"RIFF" or webp[8:12] != b"WEBP":
        raise MetadataError("the encoder's WebP is not a RIFF WEBP file")
    chunks = [(fourcc, payload) for fourcc, payload in _riff_chunks(webp)
              if fourcc not in (b"EXIF", b"XMP ")]
    if not chunks:
        raise MetadataError("the encoder's WebP has no chunks")
    first, payload = chunks[0]
    if first == b"VP8X":
        flags, header = payload[0], bytes(payload[1:])
    elif first in (b"VP8 ", b"VP8L"):
        # A lossless bitstream says whether it uses alpha (bit 28 after its signature byte);
        # a lossy one with alpha is written in the extended format already (ALPH chunk).
        uses_alpha = (first == b"VP8L" and len(payload) >= 5
                      and int.from_bytes(payload[1:5], "little") >> 28 & 1)
        flags = _VP8X_ALPHA if uses_alpha else 0
        width, height = size
        header = b"\x00\x00\x00" + (width - 1).to_bytes(3, "little") + (
            height - 1).to_bytes(3, "little")
    else:
        raise MetadataError(f"the encoder's WebP starts with an unknown chunk {first!r}")
    if exif is not None:
        flags |= _VP8X_EXIF
    if xmp is not None:
        flags |= _VP8X_XMP
    rest = chunks[1:] if first == b"VP8X" else chunks
    parts = _riff_chunk(b"VP8X", bytes((flags,)) + header)
    for fourcc, data in rest:
        parts += _riff_chunk(fourcc, data)
    if exif is not None:
        parts += _riff_chunk(b"EXIF", exif[len(EXIF_PREFIX):])
    if xmp is not None:
        parts += _riff_chunk(b"XMP ", xmp)
    size = 4 + sum(len(part) for part in parts)
    return b"".join([b"RIFF", struct.pack("<I", size), b"WEBP", *parts])  # one copy


def _with_tiff(tiff: bytes, photo: PhotoExif | None, xmp: bytes | None,
               size: tuple[int, int]) -> bytes:
    """The TIFF with the EXIF's tags and the XMP packet (tag 700) in its first IFD.

    The encoder's IFD0 entries are kept as they are (their offsets point where they did);
    the added tags, with their Exif and GPS IFDs and their values, are serialized by Pillow
    (``ImageFileDirectory_v2``) at the end of the file, and a new IFD0 of both sets of
    entries, in tag order, is written after them; the header points to it. The old IFD0
    stays behind, unreferenced (a few hundred bytes). Tags the encoder wrote win."""
    from PIL import TiffImagePlugin

    if tiff[:4] == b"II*\x00":
        order = "<"
    elif tiff[:4] == b"MM\x00*":
        order = ">"
    else:
        raise MetadataError("the encoder's TIFF is not a classic TIFF")
    first = struct.unpack(order + "I", tiff[4:8])[0]
    if first + 2 > len(tiff):
        raise MetadataError("the encoder's TIFF has no first IFD")
    count = struct.unpack(order + "H", tiff[first:first + 2])[0]
    table = first + 2
    if table + 12 * count + 4 > len(tiff):
        raise MetadataError("the encoder's TIFF has a cut first IFD")
    own = {struct.unpack(order + "H", tiff[at:at + 2])[0]: tiff[at:at + 12]
           for at in range(table, table + 12 * count, 12)}
    if struct.unpack(order + "I", tiff[table + 12 * count:table + 12 * count + 4])[0]:
        raise MetadataError("the encoder's TIFF has more than one image")
    added = TiffImagePlugin.ImageFileDirectory_v2(tiff[:8])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if photo is not None:
                ifd0, sub = _output_tags(photo, size)
                for tag, value in ifd0.items():
                    if tag not in own and tag not in (_IMAGE_WIDTH, _IMAGE_LENGTH):
                        added[tag] = value
                added[_EXIF_IFD] = sub
                if photo.gps:
                    added[_GPS_IFD] = dict(photo.gps)
            if xmp is not None:
                added[_XMP_TAG] = xmp
            start = len(tiff) + (len(tiff) & 1)
            block = added.tobytes(start)
    except Exception as error:  # noqa: BLE001 - values of untrusted bytes, Pillow's writer
        raise DamagedExifError(f"EXIF that cannot be written ({type(error).__name__})") from None
    # Pillow's block: its entry count, its entries (offsets into the block), next IFD, data.
    entries = {struct.unpack(order + "H", block[at:at + 2])[0]: block[at:at + 12]
               for at in range(2, 2 + 12 * len(added), 12)}
    entries = {tag: entry for tag, entry in entries.items() if tag not in own}
    merged = {**own, **entries}
    new_ifd = (struct.pack(order + "H", len(merged))
               + b"".join(merged[tag] for tag in sorted(merged)) + b"\x00\x00\x00\x00")
    pad = b"\x00" * ((start + len(block)) & 1)
    at = start + len(block) + len(pad)  # the new IFD0, word-aligned
    return b"".join((tiff[:4], struct.pack(order + "I", at), memoryview(tiff)[8:],
                     b"\x00" * (start - len(tiff)), block, pad, new_ifd))  # one copy


def with_metadata(encoded: bytes, extension: str, size: tuple[int, int],
                  photo: PhotoExif | None, record: Mapping[str, str] | None) -> bytes:
    """``encoded`` (a ``.jpg``, ``.png``, ``.webp`` or ``.tif`` file of ``size`` =
    ``(width, height)``, as an encoder made it) with ``photo``'s EXIF (:func:`exif_bytes`)
    and ``record`` as an XMP packet (:func:`xmp_packet`), where the format keeps them
    (module docstring); the pixels' bytes untouched. Nothing to add gives ``encoded`` itself.
    Raises :class:`DamagedExifError` for values Pillow read but cannot write, and
    :class:`MetadataError` when they cannot be added otherwise (too large for a JPEG segment,
    an encoder's file of an unexpected shape)."""
    if photo is None and not record:
        return encoded
    if extension == ".jpg":
        if not header_segments(encoded):
            raise MetadataError("the encoder's JPEG has no header to add to")
        return with_segments(encoded, jpeg_segments(size, photo, record))
    xmp = xmp_packet(record) if record else None
    if extension == ".tif":
        return _with_tiff(encoded, photo, xmp, size)
    exif = exif_bytes(photo, size) if photo is not None else None
    if extension == ".png":
        return _with_png(encoded, exif, xmp)
    if extension == ".webp":
        return _with_webp(encoded, exif, xmp, size)
    raise MetadataError(f"{extension} files hold no metadata gsrwt writes")


#: Output formats that hold metadata (:func:`with_metadata`).
METADATA_FORMATS = (".jpg", ".png", ".webp", ".tif")
