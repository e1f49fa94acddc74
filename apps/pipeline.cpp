// placeholder translation unit until the CLI lands
