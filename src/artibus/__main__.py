from artibus.cli import console

console()
