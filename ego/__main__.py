from ego._entry import run

run()
