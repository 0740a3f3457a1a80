"""The command line: the paper's inputs as a TOML scene file and an OBJ mesh, an image out."""
