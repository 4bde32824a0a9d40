/* pihyst_f32_names.h - maps every public name of pihyst.h to its single-precision twin
 * (pihyst_model -> pihyst_model_f32, ...), so that code written once for the double API
 * builds as the _f32 API. Used by the core's f32 build (pihyst_internal.h) and the
 * tests; include it after pihyst.h, and only where that is the intent. */
#ifndef PIHYST_F32_NAMES_H
#define PIHYST_F32_NAMES_H

#define pihyst_shape pihyst_shape_f32
#define pihyst_pwl pihyst_pwl_f32
#define pihyst_params pihyst_params_f32
#define pihyst_model pihyst_model_f32
#define pihyst_model_init pihyst_model_init_f32
#define pihyst_model_reset pihyst_model_reset_f32
#define pihyst_model_step pihyst_model_step_f32
#define pihyst_model_run pihyst_model_run_f32
#define pihyst_model_operators pihyst_model_operators_f32
#define pihyst_model_gram pihyst_model_gram_f32
#define pihyst_model_envelopes pihyst_model_envelopes_f32
#define pihyst_compensator pihyst_compensator_f32
#define pihyst_compensator_scratch_len pihyst_compensator_scratch_len_f32
#define pihyst_compensator_init pihyst_compensator_init_f32
#define pihyst_compensator_reset pihyst_compensator_reset_f32
#define pihyst_compensator_step pihyst_compensator_step_f32
#define pihyst_compensator_run pihyst_compensator_run_f32
#define pihyst_bank_step pihyst_bank_step_f32
#define pihyst_bank_compensate pihyst_bank_compensate_f32
#define pihyst_compbank pihyst_compbank_f32
#define pihyst_compbank_work_len pihyst_compbank_work_len_f32
#define pihyst_compbank_init pihyst_compbank_init_f32
#define pihyst_compbank_compensate pihyst_compbank_compensate_f32
#define pihyst_compbank_sync pihyst_compbank_sync_f32
#define pihyst_modelbank pihyst_modelbank_f32
#define pihyst_modelbank_work_len pihyst_modelbank_work_len_f32
#define pihyst_modelbank_init pihyst_modelbank_init_f32
#define pihyst_modelbank_step pihyst_modelbank_step_f32
#define pihyst_modelbank_sync pihyst_modelbank_sync_f32
#undef PIHYST_COMPBANK_WORK_LEN
#undef PIHYST_MODELBANK_WORK_LEN
#define PIHYST_MODELBANK_WORK_LEN PIHYST_MODELBANK_WORK_LEN_F32
#define PIHYST_COMPBANK_WORK_LEN PIHYST_COMPBANK_WORK_LEN_F32
#undef PIHYST_COMPENSATOR_SCRATCH_LEN
#define PIHYST_COMPENSATOR_SCRATCH_LEN PIHYST_COMPENSATOR_SCRATCH_LEN_F32

#endif /* PIHYST_F32_NAMES_H */
