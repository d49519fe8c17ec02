# The naive MLP baseline of constrained prediction (thesis ch 7): past -> future by MSE; engine.
target_sources(foresight_inference PRIVATE ${CMAKE_CURRENT_LIST_DIR}/naive_predictor.cc)
