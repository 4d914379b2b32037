"""The README's drive configuration (the indented block after the
<!-- drive-config: ... --> marker), as the drive tests start from it."""


def drive_config(readme_path):
    lines = open(readme_path).read().splitlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("<!-- drive-config:"))
    block = []
    for l in lines[i + 1:]:
        if not l.startswith("    "):
            break
        block.append(l[4:])
    return "\n".join(block) + "\n"
