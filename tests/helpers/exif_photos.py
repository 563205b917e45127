"""Photos with a camera's EXIF, as a phone or camera writes it: make, model, lens, dates,
exposure, GPS, an orientation, a maker's note, a subject area and a thumbnail (IFD1).

The tags are written by Pillow (``Image.Exif``); the thumbnail IFD, which Pillow does not
write, is appended here by hand (TIFF 6.0: IFD0's next-IFD offset points to IFD1, whose
``JPEGInterchangeFormat``/``Length`` point to a small JPEG). Read back in the tests by
exifread, a parser independent of Pillow and of gsrwt.
"""

from __future__ import annotations

import io
import struct
from pathlib import Path

import numpy as np
from PIL import Image
from PIL.TiffImagePlugin import IFDRational

MAKE, MODEL, LENS = "Canon", "Canon EOS 5D Mark IV", "EF24-70mm f/2.8L II USM"
TAKEN = "2024:05:06 07:08:09"
#: What exifread prints for the tags the tests check, keyed by exifread's names.
EXPECTED = {
    "Image Make": MAKE, "Image Model": MODEL, "Image DateTime": TAKEN,
    "EXIF DateTimeOriginal": TAKEN, "EXIF LensModel": LENS, "EXIF ExposureTime": "1/250",
    "EXIF FNumber": "14/5", "EXIF ISOSpeedRatings": "400", "EXIF FocalLength": "35",
    "GPS GPSLatitudeRef": "N", "GPS GPSLatitude": "[52, 30, 617/50]",
    "GPS GPSLongitudeRef": "E", "GPS GPSLongitude": "[13, 24, 5]",
}


def camera_exif(orientation: int = 1, width: int = 6000, height: int = 4000) -> bytes:
    """An EXIF block (with its ``Exif`` prefix) of a camera's photo, with a thumbnail."""
    exif = Image.Exif()
    exif[0x010F], exif[0x0110], exif[0x0112], exif[0x0132] = MAKE, MODEL, orientation, TAKEN
    exif[0x8769] = {
        0x829A: IFDRational(1, 250), 0x829D: IFDRational(28, 10), 0x8827: 400,
        0x9003: TAKEN, 0x920A: IFDRational(35, 1), 0xA434: LENS,
        0xA002: width, 0xA003: height,
        0x927C: b"maker's own notes" * 8,  # MakerNote
        0x9214: (10, 20, 30, 40),  # SubjectArea, in the input's pixels
    }
    exif[0x8825] = {
        0: b"\x02\x03\x00\x00", 1: "N",
        2: (IFDRational(52, 1), IFDRational(30, 1), IFDRational(1234, 100)), 3: "E",
        4: (IFDRational(13, 1), IFDRational(24, 1), IFDRational(5, 1)),
    }
    return with_thumbnail(exif.tobytes())


def with_thumbnail(exif: bytes) -> bytes:
    """``exif`` (with its prefix) with an IFD1 holding a 16x12 JPEG thumbnail."""
    block = exif[6:]
    order = "<" if block[:2] == b"II" else ">"
    first = struct.unpack(order + "I", block[4:8])[0]
    count = struct.unpack(order + "H", block[first:first + 2])[0]
    next_at = first + 2 + 12 * count
    thumb = io.BytesIO()
    Image.new("RGB", (16, 12), "red").save(thumb, "JPEG")
    ifd1_at = len(block) + (len(block) & 1)
    data_at = ifd1_at + 2 + 3 * 12 + 4
    short = (lambda value: value << 16) if order == ">" else (lambda value: value)
    ifd1 = struct.pack(order + "H", 3)
    ifd1 += struct.pack(order + "HHII", 0x0103, 3, 1, short(6))  # Compression: JPEG
    ifd1 += struct.pack(order + "HHII", 0x0201, 4, 1, data_at)
    ifd1 += struct.pack(order + "HHII", 0x0202, 4, 1, len(thumb.getvalue()))
    ifd1 += b"\x00\x00\x00\x00"
    patched = bytearray(block + b"\x00" * (len(block) & 1))
    patched[next_at:next_at + 4] = struct.pack(order + "I", ifd1_at)
    return b"Exif\x00\x00" + bytes(patched) + ifd1 + thumb.getvalue()


def write_camera_photo(path: Path, pixels: np.ndarray, orientation: int = 1,
                       exif: bytes | None = None) -> Path:
    """``pixels`` (RGB, 8 bits) saved by Pillow as a photo with :func:`camera_exif` (or
    ``exif``), in the format of ``path``'s suffix."""
    image = Image.fromarray(pixels)
    if exif is None:
        exif = camera_exif(orientation, image.width, image.height)
    options = {"quality": 95} if path.suffix in (".jpg", ".webp") else {}
    image.save(path, exif=exif, **options)
    return path


# --------------------------------------------------------------------------------------------
# Reading back, by other code than gsrwt's writer
# --------------------------------------------------------------------------------------------


def riff_chunk(data: bytes, fourcc: bytes) -> bytes | None:
    """The payload of a WebP's first chunk ``fourcc`` (WebP Container Specification)."""
    position = 12
    while position + 8 <= len(data):
        size = int.from_bytes(data[position + 4:position + 8], "little")
        if data[position:position + 4] == fourcc:
            return data[position + 8:position + 8 + size]
        position += 8 + size + (size & 1)
    return None


def exif_tags(data: bytes) -> dict[str, str]:
    """An image file's EXIF tags as exifread prints them (``{"Image Make": "Canon", ...}``;
    thumbnail tags as ``Thumbnail ...`` and ``JPEGThumbnail``, maker notes as ``MakerNote
    ...``). A WebP's ``EXIF`` chunk is found here and its TIFF block given to exifread, whose
    own WebP reader expects an ``Exif`` prefix the WebP specification does not have."""
    import exifread

    if data[:4] == b"RIFF":
        block = riff_chunk(data, b"EXIF")
        if block is None:
            return {}
        data = block
    tags = exifread.process_file(io.BytesIO(data))
    return {name: (value if isinstance(value, bytes) else str(value))
            for name, value in tags.items()}


def xmp_of(data: bytes) -> bytes | None:
    """An image file's XMP packet as Pillow finds it (JPEG APP1, PNG iTXt, WebP chunk, TIFF
    tag 700), or None."""
    with Image.open(io.BytesIO(data)) as image:
        packet = image.tag_v2.get(700) if image.format == "TIFF" else image.info.get("xmp")
    if isinstance(packet, str):
        packet = packet.encode()
    return packet


#: gsrwt's XMP namespace, as docs/COMMANDS.md names it.
GSRWT_NS = "urn:gsrwt:xmp:1.0#"


def gsrwt_record(packet: bytes) -> dict[str, str]:
    """The ``gsrwt:`` properties of an XMP packet, parsed as XML by the standard library."""
    import xml.etree.ElementTree as ET

    text = packet.decode()
    start, end = text.index("<x:xmpmeta"), text.index("</x:xmpmeta>") + len("</x:xmpmeta>")
    root = ET.fromstring(text[start:end])
    rdf = "{http://www.w3.org/1999/02/22-rdf-syntax-ns#}"
    record = {}
    for description in root.iter(f"{rdf}Description"):
        for name, value in description.attrib.items():
            if name.startswith("{" + GSRWT_NS + "}"):
                record[name[len(GSRWT_NS) + 2:]] = value
    return record
