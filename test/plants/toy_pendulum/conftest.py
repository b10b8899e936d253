"""The toy's law files are not a package on their own (toy.py lays them over the template)."""
collect_ignore = ["law"]
