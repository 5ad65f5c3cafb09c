"""mkdocs hooks of the magdesign site: the spec reference is generated from the code.

``spec.md`` is written at build time by :func:`magdesign.spec.reference.markdown`, from the
same table of keys that the spec reader checks, so the reference cannot drift from the code.
"""

from mkdocs.structure.files import File


def on_files(files, config):
    from magdesign.spec.reference import markdown

    files.append(File.generated(config, "spec.md", content=markdown()))
    return files
