"""Composes rendered panels into one captioned grid image (Debian's Python with PIL).

    /usr/bin/python3 bench/compose_panels.py OUT.png COLUMNS PANEL1.png CAPTION1 [PANEL2.png CAPTION2 ...]
"""
import sys

from PIL import Image, ImageDraw


def main():
    out, columns, rest = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
    panels = [(Image.open(rest[i]).convert("RGB"), rest[i + 1]) for i in range(0, len(rest), 2)]
    w, h = panels[0][0].size
    caption = 22
    rows = (len(panels) + columns - 1) // columns
    sheet = Image.new("RGB", (columns * w, rows * (h + caption)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (panel, text) in enumerate(panels):
        x, y = (i % columns) * w, (i // columns) * (h + caption)
        sheet.paste(panel, (x, y + caption))
        draw.text((x + 6, y + 5), text, fill="black")
    sheet.save(out, optimize=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
